"""The examples in python/examples run and check their reference numbers (issue 28): the
script of D Fig. 5.13 and the notebook of D Fig. 6.4, executed cell by cell as Jupyter would
(every code cell in order, in one namespace, matplotlib headless)."""

import json
import os
import subprocess
import sys

from test_pdamp import ROOT

EXAMPLES = ROOT / "python" / "examples"


def test_coupled_beam_decay_script(tmp_path):
    r = subprocess.run(
        [sys.executable, str(EXAMPLES / "coupled_beam_decay.py"), str(tmp_path)],
        capture_output=True, text=True,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert "peak ζ = 0.056" in r.stdout
    assert (tmp_path / "fig_5_13.png").stat().st_size > 10_000


def test_loss_factor_notebook(tmp_path, monkeypatch):
    nb = json.loads((EXAMPLES / "loss_factor_fig_6_4.ipynb").read_text())
    assert nb["nbformat"] == 4
    monkeypatch.setenv("PDAMP_ROOT", str(ROOT))
    monkeypatch.setenv("PDAMP_OUT", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__main__"}
    cells = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert len(cells) >= 4
    for i, cell in enumerate(cells):
        source = "".join(cell["source"])
        exec(compile(source, f"loss_factor_fig_6_4.ipynb[{i}]", "exec"), namespace)
    assert (tmp_path / "fig_6_4.png").stat().st_size > 10_000
    assert len(namespace["dem"]) == 4
