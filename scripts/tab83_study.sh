#!/usr/bin/env bash
# D Tab. 8.3 (L3361–3368), baseline columns, from drop-down beds (issue 24, must-show 5):
#  1. softened (E/100): `pdamp fields examples/damper_ch8_tab83_softened.toml` — three
#     drop-down beds, both points on each, means with 95 % CIs in fields.csv;
#  2. D's moduli: the same three beds (`pdamp settle … --packing k`, each settled at E/100),
#     read from bed.csv into examples/damper_ch8_tab83.toml, settled again at 208/70 GPa for
#     0.05 s, both points on each; the script prints the means with 95 % CIs (Student's t).
#     (A drop-down at D's moduli, Δt = 0.5 µs, costs ≈ 20 min per bed on 2 cores; the beds are
#     made at E/100 and settled at the real moduli instead.)
# Usage: scripts/tab83_study.sh OUT_DIR [THREADS]   (≈ 80 min on 2 cores)
set -euo pipefail
out=${1:?usage: scripts/tab83_study.sh OUT_DIR [THREADS]}
threads=${2:-2}
root=$(cd "$(dirname "$0")/.." && pwd)
pdamp=${PDAMP:-$root/target/release/pdamp}
mkdir -p "$out"
out=$(cd "$out" && pwd)
ln -sfn "$root/examples/cor" "$out/cor"   # the COR tables, relative to the scenarios
"$pdamp" --threads "$threads" fields "$root/examples/damper_ch8_tab83_softened.toml" \
    --out "$out/softened" --quiet --overwrite
for k in 0 1 2; do
    "$pdamp" --threads "$threads" settle "$root/examples/damper_ch8_tab83_softened.toml" \
        --packing "$k" --out "$out/bed_$k" --quiet --overwrite > /dev/null
    python3 - "$root/examples/damper_ch8_tab83.toml" "$out" "$k" <<'PY'
import re, sys
src, out, k = sys.argv[1], sys.argv[2], sys.argv[3]
s = open(src).read()
s = re.sub(r'placement = \{ method = "drop_down".*\n',
           f'placement = {{ method = "file", path = "{out}/bed_{k}/bed.csv" }}\n', s)
s = re.sub(r'\[settle\]\n(.*\n)*?\n',
           '[settle]\nmax_duration_s = 0.05\nkinetic_energy_per_particle_j = 1e-12\n\n', s, count=1)
s = re.sub(r'packings = 3 ', 'packings = 1 ', s)
open(f'{out}/real_{k}.toml', 'w').write(s)
PY
    "$pdamp" --threads "$threads" fields "$out/real_$k.toml" --out "$out/real_$k" --quiet --overwrite
done
python3 - "$out" <<'PY'
import csv, math, sys
out = sys.argv[1]
t975 = {1: 12.7062047, 2: 4.3026527, 3: 3.1824463, 4: 2.7764451}
def ci(v):
    n = len(v); m = sum(v) / n
    s = math.sqrt(sum((x - m) ** 2 for x in v) / (n - 1))
    return m, s, t975[n - 1] * s / math.sqrt(n)
print("softened (pdamp's ensemble, fields.csv):")
for r in csv.DictReader(open(f"{out}/softened/fields.csv")):
    print(f"  Γ = {float(r['intensity']):.0f}: η̄ = {float(r['effective_loss_factor']):.3f} ± "
          f"{float(r['effective_loss_factor_ci95_half_width']):.3f}, m̄/m = "
          f"{float(r['effective_mass_ratio']):.3f} ± {float(r['effective_mass_ratio_ci95_half_width']):.3f}")
real = {}
for k in range(3):
    for r in csv.DictReader(open(f"{out}/real_{k}/fields.csv")):
        real.setdefault(round(float(r['intensity'])), []).append(
            (float(r['effective_loss_factor']), float(r['effective_mass_ratio'])))
print("D's moduli (three beds):")
for g, v in sorted(real.items()):
    e, m = ci([a for a, _ in v]), ci([b for _, b in v])
    print(f"  Γ = {g}: η̄ = {e[0]:.3f} ± {e[2]:.3f} (members {', '.join(f'{a:.3f}' for a, _ in v)}), "
          f"m̄/m = {m[0]:.3f} ± {m[2]:.3f}")
PY
