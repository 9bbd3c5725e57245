"""The step-wise World (issue 28): stepped from Python it gives `pdamp run`'s numbers to the
bit, its particle views are the world's memory (no copy), a driven body moved from Python
equals the scenario's own harmonic motion to the bit, and the bed's load on its container is
its weight."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import pdamp

import pandas as pd

from test_pdamp import BIN, cli, same


def box(tmp_path, particles=300, duration_s=0.02):
    text = subprocess.run(
        [BIN, "--quiet", "example", "--particles", str(particles), "--duration-s", str(duration_s)],
        capture_output=True, text=True, check=True,
    ).stdout
    path = tmp_path / "box.toml"
    path.write_text(text)
    return path


def test_world_stepped_from_python_equals_pdamp_run(tmp_path):
    path = box(tmp_path)
    cli("run", path, "--out", tmp_path / "cli")
    summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    w = pdamp.World(pdamp.load(path), threads=2)
    assert len(w) == summary["particles"] == 300
    assert w.time_s == 0.0 and w.settling_time_s == summary["settling_time_s"]
    w.step(7)            # short calls (no watcher thread) …
    w.step(500)          # … a long one …
    w.run_until()        # … and the rest up to the scenario's duration, as `pdamp run`
    e = w.energy()
    assert e["time_s"] == summary["simulated_time_s"]
    for k, v in summary["energy"].items():
        assert e[k] == v, k                       # to the bit
    assert e["closure_error_j"] == summary["energy_closure_error_j"]
    assert abs(e["closure_error_j"]) <= 1e-3 * e["wall_work_j"]
    # pdamp.run writes what the command line writes, with the same numbers
    r = pdamp.run(pdamp.load(path), tmp_path / "py")          # all cores, as the command line
    same(r.summary, summary)
    pd.testing.assert_frame_equal(r.energy, pd.read_csv(tmp_path / "cli" / "energy.csv"))
    assert r.energy["time_s"].iloc[-1] == pytest.approx(0.02)


def test_particle_views_are_the_worlds_memory(tmp_path):
    w = pdamp.World(pdamp.load(box(tmp_path, 100, 0.005)), threads=1)
    x = w.positions_m
    assert x.shape == (100, 3) and x.dtype == np.float64
    address = x.__array_interface__["data"][0]
    assert w.positions_m.__array_interface__["data"][0] == address   # no copy per access
    assert np.shares_memory(x, w.positions_m)
    before = x.copy()
    w.step(20)
    assert x.__array_interface__["data"][0] == address
    assert not np.array_equal(x, before)          # the view follows the world
    assert not x.flags.writeable and not w.velocities_m_s.flags.writeable
    with pytest.raises(ValueError):
        x[0, 0] = 1.0
    r, m = w.radii_m, w.masses_kg
    assert r.shape == m.shape == (100,)
    # m = 4/3 π r³ ρ for every particle (ρ of the example's material)
    rho = pdamp.load(box(tmp_path, 100, 0.005)).to_dict()["materials"][0]["density_kg_m3"]
    np.testing.assert_allclose(m, 4.0 / 3.0 * math.pi * r**3 * rho, rtol=1e-14)
    base = sys.getrefcount(w)
    v = w.forces_n
    assert sys.getrefcount(w) == base + 1         # the view holds the world alive
    del w
    assert np.isfinite(v).all() and np.isfinite(x).all()


def driven_copy(path, tmp_path):
    d = pdamp.load(path).to_dict()
    body = d["bodies"][0]
    law = dict(body["motion"])
    body["motion"] = {"type": "driven"}
    return pdamp.Scenario.from_dict(d, base_dir=tmp_path), body["name"], law


def test_driven_body_equals_the_harmonic_motion_to_the_bit(tmp_path):
    # 500 spheres: some rest against the moving x walls from the start
    path = box(tmp_path, 500, 0.01)
    harmonic = pdamp.World(pdamp.load(path), threads=2)
    sc, name, law = driven_copy(path, tmp_path)
    e = np.array(law["direction"], dtype=float)
    e /= np.linalg.norm(e)
    w = 2.0 * math.pi * law["frequency_hz"]
    x = law["amplitude_m"]
    phase = law.get("phase_rad", 0.0)

    def state(t):
        a = w * t + phase
        return e * (x * math.sin(a)), e * (x * w * math.cos(a)), e * (-x * w * w * math.sin(a))

    driven = pdamp.World(sc, threads=2, drive={name: state(0.0)})   # the starting state
    assert driven.energy() == harmonic.energy()
    for _ in range(1500):
        u, v, acc = state(driven.time_s + driven.dt_s)     # the state at the end of the step
        driven.drive_body(name, u, v, acc)
        driven.step()
        harmonic.step()
    assert driven.time_s == harmonic.time_s
    assert driven.energy() == harmonic.energy()
    assert driven.body_load(name) == harmonic.body_load(name)
    assert driven.body_load(name) != ((0.0,) * 3, (0.0,) * 3)
    np.testing.assert_array_equal(driven.positions_m, harmonic.positions_m)
    with pytest.raises(ValueError, match="not driven"):
        harmonic.drive_body(name, u, v, acc)
    with pytest.raises(KeyError, match="no body"):
        driven.body_load("lid")
    with pytest.raises(ValueError, match="not a driven body"):
        pdamp.World(pdamp.load(path), drive={name: state(0.0)})


def test_bed_at_rest_weighs_on_its_container(tmp_path):
    path = box(tmp_path, 200, 0.005)
    sc, name, _ = driven_copy(path, tmp_path)
    world = pdamp.World(sc, threads=2)
    for _ in range(3000):                       # held at its reference pose, the bed settles
        world.drive_body(name, [0.0] * 3, [0.0] * 3)
        world.step()
    force, _ = world.body_load(name)
    g = np.array(sc.to_dict()["simulation"]["gravity_m_s2"])
    weight = world.masses_kg.sum() * g
    # Σ F_wall = m g at rest (the residual kinetic energy of the bed is tiny)
    np.testing.assert_allclose(force, weight, rtol=2e-3, atol=2e-3 * np.linalg.norm(weight))


def test_ctrl_c_stops_a_world_cleanly_and_it_continues_to_the_same_numbers(tmp_path):
    import os
    import signal
    import threading

    path = box(tmp_path, 300, 0.05)
    whole = pdamp.World(pdamp.load(path), threads=1)
    seen = []
    whole.run_until(progress=lambda phase, f: seen.append((phase, f)))
    assert [p for p, _ in seen] == ["running"] * len(seen) and len(seen) >= 2
    fractions = [f for _, f in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0

    w = pdamp.World(pdamp.load(path), threads=1)
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        w.run_until()
    timer.join()
    assert 0.0 < w.time_s < w.duration_s          # stopped in the middle, at a whole step
    w.check_health()
    w.run_until()                                   # the stop request is gone: runs to the end
    assert w.energy() == whole.energy()             # and the interruption changed nothing
    np.testing.assert_array_equal(w.positions_m, whole.positions_m)


def test_tqdm_bar(tmp_path, capsys):
    pytest.importorskip("tqdm")
    w = pdamp.World(pdamp.load(box(tmp_path, 100, 0.01)), threads=1)
    from tqdm import tqdm

    bar = pdamp._Bar(tqdm)
    w.run_until(progress=bar)
    bar.close()
    err = capsys.readouterr().err
    assert "running" in err and "100%" in err


def test_a_deformable_wall_moved_from_python_returns_nodal_forces(tmp_path):
    """A plate on the box floor (a `box_outside` mesh of its own body) is lifted from Python by
    moving its vertices: the nodal forces handed back sum to the bed's load on the plate's body
    (round-off), every step, and carry the bed's weight at rest."""
    d = pdamp.load(box(tmp_path, 200, 0.01)).to_dict()
    d["bodies"][0]["motion"] = {"type": "fixed"}
    d["bodies"].append({
        "name": "piston", "position_m": [0.0, 0.0, 0.0], "motion": {"type": "fixed"},
        "walls": [{"name": "plate", "material": d["materials"][0]["name"],
                   "geometry": {"type": "box_outside", "center_m": [0.0, 0.0, 0.001],
                                "half_extents_m": [0.019, 0.019, 0.001]}}],
    })
    region = d["particles"][0]["placement"]["region"]
    region["min_m"][2] = 0.0025                    # the bed starts above the plate
    d["settle"]["max_duration_s"] = 0.08
    w = pdamp.World(pdamp.Scenario.from_dict(d, base_dir=tmp_path), threads=2)
    v0 = w.wall_vertices("piston", "plate")
    assert v0.shape == (8, 3)
    weight = w.masses_kg.sum() * 9.81
    # at rest after settling: the plate carries (nearly all of) the bed's weight
    f = w.wall_nodal_forces("piston", "plate")
    np.testing.assert_allclose(f.sum(axis=0), w.body_load("piston")[0], rtol=1e-12, atol=1e-15)
    assert f.sum(axis=0)[2] < 0 and abs(f.sum(axis=0)[2] + weight) < 0.05 * weight
    lift, steps = 1e-3, 2000
    pushed = 0.0
    for k in range(1, steps + 1):                   # lift the plate by 1 mm (it throws the bed)
        v = v0.copy()
        v[:, 2] += lift * k / steps
        w.move_wall_vertices("piston", "plate", v)
        w.step()
        f = w.wall_nodal_forces("piston", "plate")
        np.testing.assert_allclose(f.sum(axis=0), w.body_load("piston")[0], rtol=1e-12, atol=1e-15)
        pushed = max(pushed, -f[:, 2].sum())
    np.testing.assert_array_equal(w.wall_vertices("piston", "plate")[:, 2], v0[:, 2] + lift)
    assert pushed > weight                          # accelerating the bed upwards takes more
    with pytest.raises(ValueError, match="not a triangle mesh"):
        w.wall_vertices("box", "container")
    with pytest.raises(ValueError, match="vertices"):
        w.move_wall_vertices("piston", "plate", v0[:4])
    with pytest.raises(KeyError, match="no wall"):
        w.wall_nodal_forces("piston", "lid")
