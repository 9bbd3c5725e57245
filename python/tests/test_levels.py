"""Every level of the toolchain from Python against the command line (issue 28): single
impacts, restitution curves, structural modes, coupled structures (formulas and full DEM) and
powder cavities give the command line's numbers to the bit; bad inputs name the argument;
progress reaches a callback."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import pdamp

from test_pdamp import EXAMPLES, ROOT, cli, same


def test_impact_equals_cli_and_names_bad_inputs():
    args = dict(radius_m=0.001, youngs_modulus_pa=2.1e11, poisson_ratio=0.3, density_kg_m3=7850.0, velocity_m_s=0.5)
    r = pdamp.impact(**args, law="gonthier", restitution=0.8)
    c = json.loads(cli("impact", "--radius-m", 0.001, "--youngs-modulus-pa", 2.1e11, "--poisson-ratio", 0.3,
                       "--density-kg-m3", 7850.0, "--velocity-m-s", 0.5, "--law", "gonthier", "--restitution", 0.8))
    same(r, c)
    assert r["restitution"] == pytest.approx(0.8, abs=1e-6)          # Gonthier reproduces ε [D Eq. 2.79]
    h = pdamp.impact(**args)                                            # elastic Hertz: D Eq. 4.8, 2.80
    assert h["contact_time_s"] == pytest.approx(h["hertz_contact_time_s"], rel=0.03)
    assert h["max_overlap_m"] == pytest.approx(h["hertz_max_overlap_m"], rel=1e-3)
    with pytest.raises(ValueError, match="velocity_m_s must lie in"):
        pdamp.impact(**{**args, "velocity_m_s": -1.0})
    with pytest.raises(ValueError, match="law must be one of"):
        pdamp.impact(**args, law="hooke")


def test_cor_equals_cli(tmp_path):
    df = pdamp.cor("s235", "s235", 0.003, [0.5, 0.1, 1.0], model="hertz")
    cli("cor", "--sphere", "s235", "--wall", "s235", "--sphere-radius-m", 0.003, "--velocities-m-s", "0.5,0.1,1.0",
        "--model", "hertz", "--out", tmp_path / "cor")
    c = pd.read_csv(tmp_path / "cor" / "cor.csv")
    assert list(df["velocity_m_s"]) == [0.1, 0.5, 1.0]
    for k in c.columns:
        assert np.array_equal(df[k].to_numpy(), c[k].to_numpy()), k
    assert (df["restitution"] == 1.0).all()                              # elastic Hertz
    th = pdamp.cor("s235", "s235", 0.003, [0.5], model="thornton")
    assert 0.0 < th["restitution"][0] < 1.0                              # plastic above first yield
    assert np.isnan(th["contact_time_s"][0])                             # Thornton's closed form gives none
    with pytest.raises(ValueError, match="sphere_radius_m must lie in"):
        pdamp.cor("s235", "s235", 3.0, [0.5], model="hertz")
    with pytest.raises(ValueError, match="wall"):
        pdamp.cor("s235", "unobtainium", 0.003, [0.5], model="hertz")


def test_structure_modes_equal_cli(tmp_path):
    s = EXAMPLES / "structure_cantilever_small.toml"
    r = pdamp.structure_modes(s, tmp_path / "py")
    c = json.loads(cli("structure", "modes", s, "--out", tmp_path / "cli"))
    same(r.summary, c)
    pd.testing.assert_frame_equal(r.modes, pd.read_csv(tmp_path / "cli" / "modes.csv"))
    assert "modes" in r.tables


def test_couple_formulas_and_dem_equal_cli(tmp_path):
    for name in ("couple_ch5_free_formulas", "couple_ch8_dem_rigid_small"):
        s = EXAMPLES / f"{name}.toml"
        seen = []
        r = pdamp.couple(s, tmp_path / name / "py", threads=2, progress=lambda phase, f: seen.append((phase, f)))
        c = json.loads(cli("couple", s, "--out", tmp_path / name / "cli"))
        same(r.summary, c)
        pd.testing.assert_frame_equal(r.decay, pd.read_csv(tmp_path / name / "cli" / "decay.csv"))
        assert r.frf is None                                              # a free decay writes no FRF
        assert seen and seen[-1][1] == pytest.approx(1.0) and all(0.0 <= f <= 1.0 for _, f in seen)
    with pytest.raises(pdamp.ScenarioError):
        pdamp.couple(EXAMPLES / "damper_cylinder_small.toml", tmp_path / "bad")


def test_powder_run_equals_cli(tmp_path):
    s = ROOT / "crates" / "pdamp-powder" / "tests" / "data" / "tiny_cantilever.toml"
    r = pdamp.powder_run(s, tmp_path / "py", threads=2)
    c = json.loads(cli("powder", "run", s, "--out", tmp_path / "cli"))
    same(r.summary, c)
    pd.testing.assert_frame_equal(r.tip, pd.read_csv(tmp_path / "cli" / "tip.csv"))
    # 58 particles: the draw of seed 1 from pdamp-dem's size distribution (ChaCha8)
    assert r["particles"] == 58 and len(r.tip) > 0 and np.isfinite(r["energy_closure"])
