#!/usr/bin/env bash
# Side by side: the slope at the paper's settings (scenes/slope.ron, or scenes/slope_3d.ron
# with `3d`) and its fast preset (scenes/slope_fast.ron, scenes/slope_3d_fast.ron), run in
# turn N times each (default 3) on the same machine, with the figures of
# docs/performance.md: wall seconds (median), steps, surface angle and crest u_x, and the
# wall-time ratio of each pair.
#   benches/slope_fast.sh [3d] [N] [--threads T]
set -euo pipefail
cd "$(dirname "$0")/.."
ref=slope
if [ "${1:-}" = 3d ]; then
    ref=slope_3d
    shift
fi
fast=${ref}_fast
n=${1:-3}
shift || true
cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for i in $(seq 1 "$n"); do
    for s in "$ref" "$fast"; do
        target/release/kdmpm run "scenes/$s.ron" --out "$out/$s-$i" --quiet "$@"
    done
done
python3 - "$out" "$n" "$ref" "$fast" <<'PY'
import json, statistics, sys
out, n, ref, fast = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
def load(s, i):
    d = json.load(open(f"{out}/{s}-{i}/summary.json"))
    crest = next(t for t in d["traced"] if t["name"] == "crest")
    return d["outcome"], d["wall_seconds"], d["steps"], d["surface_angle"]["degrees"], crest["displacement"][0]
rows = {s: [load(s, i) for i in range(1, n + 1)] for s in (ref, fast)}
for s, r in rows.items():
    o, w, st, a, c = r[0]
    print(f"{s:16s} {o:9s} steps {st:6d}  wall median {statistics.median(x[1] for x in r):6.2f} s "
          f"(min {min(x[1] for x in r):.2f}, max {max(x[1] for x in r):.2f})  angle {a:.3f}°  crest u_x {c:.3f} m")
ratios = [a[1] / b[1] for a, b in zip(rows[ref], rows[fast])]
print(f"wall ratio {ref}/{fast} per pair: {', '.join(f'{r:.2f}' for r in ratios)} (median {statistics.median(ratios):.2f})")
r0, f0 = rows[ref][0], rows[fast][0]
print(f"fast - reference: angle {f0[3] - r0[3]:+.3f}°, crest u_x {100 * (f0[4] / r0[4] - 1):+.2f} %")
PY
