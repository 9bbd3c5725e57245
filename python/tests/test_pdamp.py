"""Tests of the Python package against the command line (issue 28).

`PDAMP_BIN` names the `pdamp` binary of the same build (scripts/test.sh sets it); the results
of the library called from Python must equal the command line's, every number but the timing.
"""

import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import pdamp

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
SMALL = EXAMPLES / "damper_cylinder_small.toml"
BIN = os.environ.get("PDAMP_BIN", str(ROOT / "target" / "release" / "pdamp"))


def cli(*args):
    r = subprocess.run([BIN, "--quiet", *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout


def same(a, b, path=""):
    """Equal to the bit, timing fields (wall times, speed) aside."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            if "wall_time" not in k and k != "particle_steps_per_s":
                same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and math.isnan(a):
        assert isinstance(b, float) and math.isnan(b), path
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def test_version_is_the_crates():
    cargo = (ROOT / "Cargo.toml").read_text()
    version = cargo.split("[workspace.package]")[1].split('version = "')[1].split('"')[0]
    assert pdamp.__version__ == version


def test_a_scenario_round_trips_through_a_dict_and_toml():
    sc = pdamp.load(SMALL)
    assert sc.title.startswith("small cylinder damper")
    d = sc.to_dict()
    assert d["particles"][0]["count"] == 300
    again = pdamp.Scenario.from_dict(d, base_dir=sc.base_dir)
    assert again.to_toml() == sc.to_toml()
    assert pdamp.Scenario.from_toml(sc.to_toml(), base_dir=sc.base_dir).to_dict() == d
    # a change made in the dict is the scenario's
    d["damper"]["cycles"] = 5
    assert pdamp.Scenario.from_dict(d, base_dir=sc.base_dir).to_dict()["damper"]["cycles"] == 5


def test_a_bad_key_or_value_raises_scenario_error_naming_it():
    d = pdamp.load(SMALL).to_dict()
    d["simulation"]["time_stepp_s"] = 1e-6
    with pytest.raises(pdamp.ScenarioError, match="time_stepp_s"):
        pdamp.Scenario.from_dict(d)
    d = pdamp.load(SMALL).to_dict()
    d["simulation"]["time_step_s"] = -1.0
    with pytest.raises(pdamp.ScenarioError, match=r"simulation\.time_step_s"):
        pdamp.Scenario.from_dict(d)
    with pytest.raises(pdamp.ScenarioError, match="line"):
        pdamp.Scenario.from_toml('title = "x"\n[simulation]\nduration_s = -1.0\ntime_step_s = 1e-6\n')
    assert issubclass(pdamp.ScenarioError, ValueError)
    with pytest.raises(TypeError, match="simulation.seed"):
        pdamp.Scenario.from_dict({"simulation": {"seed": object()}})


def test_a_damper_point_equals_the_command_lines_summary(tmp_path):
    cli("run", SMALL, "--out", tmp_path / "cli")
    want = json.loads((tmp_path / "cli" / "summary.json").read_text())
    got = pdamp.damper_point(pdamp.load(SMALL), tmp_path / "py", threads=2)
    same(got, want)
    assert 0.0 < got["effective_loss_factor"] < 4.0 / math.pi
    # another excitation given from Python is the command line's option (the Ch. 6 box: 1 s)
    ch6 = EXAMPLES / "damper_ch6_small.toml"
    cli("run", ch6, "--out", tmp_path / "cli2", "--frequency-hz", "8", "--intensity", "5")
    want = json.loads((tmp_path / "cli2" / "summary.json").read_text())
    got = pdamp.damper_point(pdamp.load(ch6), tmp_path / "py2", frequency_hz=8.0, intensity=5.0)
    same(got, want)
    assert got["frequency_hz"] == 8.0


def test_fields_are_a_dataframe_equal_to_the_command_lines_fields_csv(tmp_path):
    pd = pytest.importorskip("pandas")
    text = SMALL.read_text()
    text = text.replace(
        'frequencies_hz = { from = 40.0, to = 160.0, count = 3, spacing = "log" }', "frequencies_hz = [160.0]"
    ).replace('intensities = { from = 2.0, to = 20.0, count = 3, spacing = "log" }', "intensities = [5.0, 20.0]")
    assert "frequencies_hz = [160.0]" in text
    scenario = tmp_path / "tiny.toml"
    scenario.write_text(text)
    cli("fields", scenario, "--out", tmp_path / "cli")
    want = pd.read_csv(tmp_path / "cli" / "fields.csv", dtype=float)
    df = pdamp.fields(pdamp.load(scenario), tmp_path / "py")
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == list(want.columns)
    assert len(df) == 2
    cols = [c for c in df.columns if c != "wall_time_s"]
    # read back by pandas from text (17 significant digits) and returned by the library: equal
    pd.testing.assert_frame_equal(df[cols], want[cols], check_exact=True)
    arrays = pdamp.fields(pdamp.load(scenario), tmp_path / "py", as_frame=False)
    assert isinstance(arrays["effective_loss_factor"], np.ndarray)
    assert arrays["effective_loss_factor"].dtype == np.float64


def test_the_gil_is_released_and_ctrl_c_stops_a_run(tmp_path):
    import signal
    import threading
    import time

    sc = pdamp.load(SMALL)
    # Another Python thread runs while a damper point computes (the GIL is released).
    ticks = []
    done = threading.Event()

    def run():
        pdamp.damper_point(sc, tmp_path / "bg", threads=1)
        done.set()

    t = threading.Thread(target=run)
    t.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.01)
    t.join()
    assert len(ticks) > 50, len(ticks)
    full = ticks[-1] - ticks[0]

    # Ctrl-C (SIGINT to this process) stops the run: KeyboardInterrupt, sooner than a whole run.
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        pdamp.damper_point(sc, tmp_path / "stopped", threads=1)
    stopped = time.perf_counter() - start
    timer.join()
    assert stopped < full, (stopped, full)
    # The next run is not stopped by the old request and gives the same numbers.
    again = pdamp.damper_point(sc, tmp_path / "again", threads=1)
    first = json.loads((tmp_path / "bg" / "summary.json").read_text())
    same(again, first)


def test_every_example_scenario_reads_back_to_the_same_bits():
    """Written and read again — through a dict or TOML — every example is the same scenario
    (same canonical TOML, so the same digest); normalised wall normals stay as written."""
    n = 0
    for path in sorted(EXAMPLES.glob("*.toml")):
        try:
            sc = pdamp.load(path)
        except pdamp.ScenarioError:
            continue  # structure, couple and powder files are other kinds
        text = sc.to_toml()
        assert pdamp.Scenario.from_dict(sc.to_dict(), base_dir=sc.base_dir).to_toml() == text, path
        assert pdamp.Scenario.from_toml(text, base_dir=sc.base_dir).to_toml() == text, path
        n += 1
    assert n >= 40, n
