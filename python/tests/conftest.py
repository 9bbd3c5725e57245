"""Shared test set-up.

Ctrl-C is Python's SIGINT handler raising KeyboardInterrupt; a process started in the background
of a non-interactive shell (CI runners, `cmd &`) inherits SIGINT ignored, and Python then installs
no handler. The tests put the interactive handler in place, as a terminal or a notebook has it.
"""

import signal

import pytest


@pytest.fixture(autouse=True, scope="session")
def interactive_ctrl_c():
    before = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)
