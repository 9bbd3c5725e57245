"""Overhead of the Python layer on the 2 000-sphere shaken box (issue 28, must-show 3).

Four copies of the same world advance through the same steps, chunk by chunk in turn (so that
machine noise hits them alike); they compute identical numbers (checked at the end), so any
difference in time is the cost of the calling layer:

* ``rust``:     ``w.step(N)`` — one call, the steps looped in Rust (the reference);
* ``python``:   ``for _ in range(N): w.step()`` — one Python call per step (the worst case);
* ``coupling``: per step ``drive_body`` + ``step`` + ``body_load`` — a user's own structure model
  moving the container (a driven copy of the box, harmonic motion computed in Python);
* ``run_until``: ``w.run_until(t)`` — the main loop of ``pdamp run`` (deferred half kicks).

    python python/benchmarks/overhead.py [--particles 2000] [--chunks 6] [--steps 500] [--threads 2]

Prints the median time per step of each and the overhead relative to ``rust``.
"""

import argparse
import math
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import pdamp

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--particles", type=int, default=2000)
    ap.add_argument("--chunks", type=int, default=6)
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--pdamp", default=str(ROOT / "target" / "release" / "pdamp"))
    a = ap.parse_args()
    text = subprocess.run(
        [a.pdamp, "--quiet", "example", "--particles", str(a.particles), "--duration-s", "10"],
        capture_output=True, text=True, check=True,
    ).stdout
    sc = pdamp.Scenario.from_toml(text)
    d = sc.to_dict()
    body = d["bodies"][0]
    law = dict(body["motion"])
    body["motion"] = {"type": "driven"}
    driven_sc = pdamp.Scenario.from_dict(d)
    name = body["name"]
    n = math.sqrt(sum(c * c for c in law["direction"]))
    e = [c / n for c in law["direction"]]
    om, x, ph = 2 * math.pi * law["frequency_hz"], law["amplitude_m"], law.get("phase_rad", 0.0)

    def state(t):  # the user's structure model: here the harmonic law, in plain Python
        s, c = math.sin(om * t + ph), math.cos(om * t + ph)
        return [k * (x * s) for k in e], [k * (x * om * c) for k in e], [k * (-x * om * om * s) for k in e]

    t0 = time.perf_counter()
    worlds = {k: pdamp.World(sc, threads=a.threads) for k in ("rust", "python", "run_until")}
    worlds["coupling"] = pdamp.World(driven_sc, threads=a.threads, drive={name: state(0.0)})
    print(f"{a.particles} spheres, {a.threads} threads; built and settled 4 worlds in {time.perf_counter() - t0:.1f} s")
    dt = worlds["rust"].dt_s

    def rust(w, n):
        w.step(n)

    def python(w, n):
        step = w.step
        for _ in range(n):
            step()

    def coupling(w, n):
        for _ in range(n):
            u, v, acc = state(w.time_s + dt)
            w.drive_body(name, u, v, acc)
            w.step()
            w.body_load(name)

    def run_until(w, n):
        w.run_until(w.time_s + n * dt)

    runs = {"rust": rust, "python": python, "coupling": coupling, "run_until": run_until}
    times = {k: [] for k in runs}
    for _ in range(a.chunks):
        for k, f in runs.items():
            t = time.perf_counter()
            f(worlds[k], a.steps)
            times[k].append((time.perf_counter() - t) / a.steps)
    ref = statistics.median(times["rust"])
    for k, ts in times.items():
        m = statistics.median(ts)
        print(f"{k:10s} {1e6 * m:8.1f} µs/step   {100 * (m / ref - 1):+6.2f} % vs rust   (chunks: {', '.join(f'{1e6 * t:.0f}' for t in ts)})")
    # The user's model alone (the part of `coupling` that is not pdamp's).
    t = time.perf_counter()
    for k in range(a.steps):
        state(k * dt)
    print(f"{'(state())':10s} {1e6 * (time.perf_counter() - t) / a.steps:8.1f} µs/step   the user's model in `coupling`")
    # Stepped by step counts, three did the same physics to the bit (`run_until` ends its chunks
    # at times, n·dt after the last, which rounds differently from n additions of dt).
    energies = {k: w.energy() for k, w in worlds.items()}
    same = all(energies[k] == energies["rust"] for k in ("python", "coupling"))
    print("rust, python and coupling identical to the bit:", same)
    for k in ("python", "coupling"):
        diff = {q: (energies["rust"][q], energies[k][q]) for q in energies[k] if energies[k][q] != energies["rust"][q]}
        if diff:
            print(f"  {k} differs: {diff}")
    if not same:
        sys.exit(1)


if __name__ == "__main__":
    main()
