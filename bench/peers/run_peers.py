#!/usr/bin/env python3
"""Peer benchmark: pdamp against LIGGGHTS on the shaken box (see README.md here).

For every particle count N the bed is built and settled once by pdamp (box at rest, 20 ms) and
written as a LIGGGHTS case, so both codes start the shaking from the same state. Then each code
runs the same number of steps with 1 and 2 threads / MPI ranks. The script prints the
particle-timesteps per second of both, their ratio, and the dissipated power of the bed from the
energy balance P = (W_box - dE_kin - dE_pot) / T of each code, which must agree within 10 %.

Usage: python3 bench/peers/run_peers.py [--sizes 1000,8000,32000] [--threads 1,2]
                                        [--steps 5000] [--work target/peers]
                                        [--compare-bin LABEL=PATH ...]
(PDAMP_BIN=path/to/pdamp skips the release build. --compare-bin runs further pdamp binaries,
e.g. the build of an earlier commit or other profile settings, in the same rounds, interleaved
with the main one and LIGGGHTS: a before/after comparison in one run.)
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def sh(cmd, **kw):
    return subprocess.run(cmd, check=True, text=True, capture_output=True, **kw)


def ensure_liggghts():
    if shutil.which("liggghts") and shutil.which("mpirun"):
        return
    print("installing LIGGGHTS (Debian package liggghts) ...", file=sys.stderr)
    prefix = [] if os.geteuid() == 0 else ["sudo"]
    subprocess.run(prefix + ["apt-get", "update"], check=False)
    subprocess.run(prefix + ["apt-get", "install", "-y", "liggghts"], check=True)


def _spin(n):
    x = 0
    for i in range(n):
        x = (x + (i ^ (x >> 3))) & 0xFFFFFFFF  # stays a machine-size integer
    return x


def parallel_capacity(n=6_000_000):
    """Speed-up of this machine itself from 1 to 2 processes on a pure CPU loop (no memory
    traffic): the ceiling for any code's 1 -> 2 thread speed-up here (shared or throttled
    virtual cores give less than 2)."""
    import multiprocessing as mp
    t0 = time.perf_counter()
    _spin(n)
    t1 = time.perf_counter() - t0
    with mp.Pool(2) as pool:
        t0 = time.perf_counter()
        pool.map(_spin, [n, n])
        t2 = time.perf_counter() - t0
    return 2.0 * t1 / t2


def cpu_times():
    """Aggregate CPU time counters of /proc/stat (jiffies): (steal, total); None off Linux."""
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    return v[7] if len(v) > 7 else 0, sum(v[:8])


def steal_fraction(before, after):
    """Share of the machine's CPU time taken by the hypervisor for other guests between two
    `cpu_times()` readings (steal time): on a shared VM a run with steal time measures the
    neighbours as much as the code, and a thread that is descheduled stalls the other at
    every synchronisation (2 threads can then run slower than 1)."""
    if before is None or after is None or after[1] <= before[1]:
        return float("nan")
    return (after[0] - before[0]) / (after[1] - before[1])


def pdamp_binary():
    if os.environ.get("PDAMP_BIN"):
        return os.environ["PDAMP_BIN"]
    sh(["cargo", "build", "--release", "-p", "pdamp-cli"], cwd=ROOT)
    return os.path.join(ROOT, "target", "release", "pdamp")


def run_pdamp(exe, n, steps, threads, settled, export=None):
    cmd = [exe, "--threads", str(threads), "bench", "--particles", str(n), "--steps",
           str(steps), "--settled", settled, "--peer"]
    if export:
        cmd += ["--export-liggghts", export]
    c0 = cpu_times()
    out = sh(cmd).stdout
    r = json.loads(out)  # pdamp prints one pretty-printed JSON object on stdout
    r["steal_fraction"] = steal_fraction(c0, cpu_times())
    return r


def run_liggghts(case_dir, ranks):
    mpi = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)]
    if ranks == 1:
        mpi = ["mpirun", "--allow-run-as-root", "-np", "1"]
    t0 = time.time()
    c0 = cpu_times()
    log = subprocess.run(mpi + ["liggghts", "-in", "in.shaken_box"], cwd=case_dir, text=True,
                         capture_output=True)
    if log.returncode != 0:
        raise RuntimeError(f"LIGGGHTS failed in {case_dir}:\n{log.stdout[-3000:]}\n{log.stderr[-3000:]}")
    steal = steal_fraction(c0, cpu_times())
    text = log.stdout
    m = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
    loop_s, steps, atoms = float(m.group(1)), int(m.group(3)), int(m.group(4))
    # thermo lines: step atoms ke rke pe cad[1]
    rows = []
    for line in text.splitlines():
        parts = line.split()
        if len(parts) == 6 and parts[0].isdigit():
            try:
                rows.append([float(x) for x in parts])
            except ValueError:
                pass
    first, last = rows[0], rows[-1]
    case = json.load(open(os.path.join(case_dir, "case.json")))
    dt, amp, freq = case["time_step_s"], case["amplitude_m"], case["frequency_hz"]
    w = 2 * math.pi * freq
    forces = []
    for line in open(os.path.join(case_dir, "force.txt")):
        if line.startswith("#"):
            continue
        k, fx, fy, fz = line.split()
        forces.append((int(k), float(fx)))
    # Work of the box on the bed: -integral of F_on_box . v_box dt (trapezoidal rule).
    forces = [f for f in forces if 0 <= f[0] <= steps]
    if forces[0][0] != 0:
        forces.insert(0, (0, 0.0))
    work = 0.0
    for (k0, f0), (k1, f1) in zip(forces, forces[1:]):
        p0 = -f0 * amp * w * math.cos(w * k0 * dt)
        p1 = -f1 * amp * w * math.cos(w * k1 * dt)
        work += 0.5 * (p0 + p1) * (k1 - k0) * dt
    d_kin = (last[2] + last[3]) - (first[2] + first[3])
    d_pot = last[4] - first[4]
    duration = steps * dt
    return {
        "particles": atoms,
        "steps": steps,
        "ranks": ranks,
        "wall_time_s": loop_s,
        "particle_steps_per_s": atoms * steps / loop_s,
        "wall_work_j": work,
        "delta_kinetic_j": d_kin,
        "delta_potential_j": d_pot,
        "dissipated_balance_j": work - d_kin - d_pot,
        "dissipated_power_w": (work - d_kin - d_pot) / duration,
        "atoms_left": int(last[1]),
        "elapsed_s": time.time() - t0,
        "steal_fraction": steal,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="1000,8000,32000")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--work", default=os.path.join(ROOT, "target", "peers"))
    ap.add_argument("--repeat", type=int, default=1, help="runs per configuration (best time is kept)")
    ap.add_argument("--compare-bin", action="append", default=[], metavar="LABEL=PATH",
                    help="a further pdamp binary run in the same rounds (repeatable)")
    args = ap.parse_args()
    compare = [tuple(x.split("=", 1)) for x in args.compare_bin]
    ensure_liggghts()
    exe = pdamp_binary()
    capacity = parallel_capacity()
    print(f"this machine: 1 -> 2 processes on a pure CPU loop: speed-up {capacity:.2f}", flush=True)
    os.makedirs(args.work, exist_ok=True)
    results = []
    for n in [int(x) for x in args.sizes.split(",")]:
        d = os.path.join(args.work, f"n{n}")
        os.makedirs(d, exist_ok=True)
        settled = os.path.join(d, "settled.bin")
        case = os.path.join(d, "liggghts")
        print(f"N = {n}: settling (once) and writing the LIGGGHTS case ...", file=sys.stderr)
        run_pdamp(exe, n, args.steps, max(int(t) for t in args.threads.split(",")), settled, case)
        # All thread counts within every repeat, so that each configuration sees the machine
        # in the same states (its speed drifts over minutes on a shared VM); best time kept.
        threads = [int(x) for x in args.threads.split(",")]
        best = {t: [None, None] for t in threads}
        best_cmp = {(t, label): None for t in threads for label, _ in compare}
        runs = {t: [] for t in threads}
        for _ in range(args.repeat):
            for t in threads:
                p = run_pdamp(exe, n, args.steps, t, settled)
                for label, other in compare:
                    c = run_pdamp(other, n, args.steps, t, settled)
                    print(f"  N={n} threads={t}: [{label}] pdamp {c['particle_steps_per_s']:.3e}",
                          file=sys.stderr, flush=True)
                    if best_cmp[(t, label)] is None or c["wall_time_s"] < best_cmp[(t, label)]["wall_time_s"]:
                        best_cmp[(t, label)] = c
                l = run_liggghts(case, t)
                runs[t].append({"pdamp_particle_steps_per_s": p["particle_steps_per_s"],
                                "pdamp_steal_fraction": p["steal_fraction"],
                                "liggghts_particle_steps_per_s": l["particle_steps_per_s"],
                                "liggghts_steal_fraction": l["steal_fraction"]})
                print(f"  N={n} threads={t}: pdamp {p['particle_steps_per_s']:.3e} (steal "
                      f"{100 * p['steal_fraction']:.0f} %), LIGGGHTS {l['particle_steps_per_s']:.3e} "
                      f"(steal {100 * l['steal_fraction']:.0f} %)", file=sys.stderr, flush=True)
                if best[t][0] is None or p["wall_time_s"] < best[t][0]["wall_time_s"]:
                    best[t][0] = p
                if best[t][1] is None or l["wall_time_s"] < best[t][1]["wall_time_s"]:
                    best[t][1] = l
        for t in threads:
            best_p, best_l = best[t]
            ratio = best_p["particle_steps_per_s"] / best_l["particle_steps_per_s"]
            diff = best_p["dissipated_power_w"] / best_l["dissipated_power_w"] - 1.0
            row = {"particles": n, "threads": t, "steps": args.steps, "pdamp": best_p,
                   "liggghts": best_l, "runs": runs[t], "speed_ratio": ratio, "dissipated_power_difference": diff,
                   "same_physics": abs(diff) <= 0.10}
            row["compare"] = {}
            for label, _ in compare:
                c = best_cmp[(t, label)]
                row["compare"][label] = {
                    "particle_steps_per_s": c["particle_steps_per_s"],
                    "speed_ratio_to_liggghts": c["particle_steps_per_s"] / best_l["particle_steps_per_s"],
                    "main_over_this": best_p["particle_steps_per_s"] / c["particle_steps_per_s"],
                    "dissipated_power_w": c["dissipated_power_w"],
                }
                print(f"N={n:6d} threads={t}: [{label}] pdamp {c['particle_steps_per_s']:.3e} p-steps/s, "
                      f"ratio to LIGGGHTS {row['compare'][label]['speed_ratio_to_liggghts']:.2f}; main build / "
                      f"{label} = {row['compare'][label]['main_over_this']:.3f}; P_diss {c['dissipated_power_w']:.4g} W",
                      flush=True)
            results.append(row)
            print(f"N={n:6d} threads={t}: pdamp {best_p['particle_steps_per_s']:.3e} p-steps/s, "
                  f"LIGGGHTS {best_l['particle_steps_per_s']:.3e} p-steps/s, ratio {ratio:.2f}; "
                  f"P_diss pdamp {best_p['dissipated_power_w']:.4g} W, LIGGGHTS "
                  f"{best_l['dissipated_power_w']:.4g} W ({100 * diff:+.1f} %); steal time "
                  f"{100 * best_p['steal_fraction']:.0f} % / {100 * best_l['steal_fraction']:.0f} %",
                  flush=True)
    # Thread scaling.
    for n in sorted({r["particles"] for r in results}):
        rs = {r["threads"]: r for r in results if r["particles"] == n}
        if 1 in rs and 2 in rs:
            sp = rs[2]["pdamp"]["particle_steps_per_s"] / rs[1]["pdamp"]["particle_steps_per_s"]
            sl = rs[2]["liggghts"]["particle_steps_per_s"] / rs[1]["liggghts"]["particle_steps_per_s"]
            print(f"N={n:6d}: speed-up 1 -> 2 threads: pdamp {sp:.2f}, LIGGGHTS {sl:.2f}")
    steals = [r[k]["steal_fraction"] for r in results for k in ("pdamp", "liggghts")]
    if any(x > 0.05 for x in steals if x == x):
        print("warning: the hypervisor took more than 5 % of the CPU time (steal) during some "
              "runs: their times and the thread speed-ups measure the neighbours too",
              file=sys.stderr)
    out = os.path.join(args.work, "results.json")
    with open(out, "w") as f:
        json.dump({"load_average": os.getloadavg(), "machine_parallel_capacity": capacity,
                   "results": results}, f, indent=2)
    print(f"results in {out}", file=sys.stderr)
    if not all(r["same_physics"] for r in results):
        print("dissipated power differs by more than 10 % somewhere", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
