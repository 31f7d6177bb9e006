#!/usr/bin/env bash
# The byte budget of a step (docs/performance.md, "The byte budget"): for each system, the
# bytes of point and node columns it reads and writes a particle-step (counted by the
# systems, `kdmpm run --profile`), its time and the rate it moves them at, set against the
# machine's STREAM triad measured in the same run. Cases: the 1M block (3D, linear shape)
# under MUSL, USL and USF, and the 2D slope (B-splines, Mohr-Coulomb) under MUSL; each run
# N times in turn (default 3), the median time of each system kept.
#   benches/byte_budget.sh [N] [--threads T]   (T default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-3}
shift || true
threads=2
if [ "${1:-}" = --threads ]; then
    threads=$2
fi
cargo build --release --quiet
cargo bench -p kdmpm-bench --bench stream --no-run --quiet 2>/dev/null
stream=$(cargo bench -p kdmpm-bench --bench stream --quiet 2>/dev/null | awk -v t="$threads" '$1 == t {print $5}')
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
cases=(
    "block_musl scenes/block_1m.ron --set solver.max_steps=30 --set solver.scheme=Musl"
    "block_usl scenes/block_1m.ron --set solver.max_steps=30 --set solver.scheme=Usl"
    "block_usf scenes/block_1m.ron --set solver.max_steps=30 --set solver.scheme=Usf"
    "slope_musl scenes/slope.ron --set solver.max_steps=600"
)
for i in $(seq 1 "$n"); do
    for c in "${cases[@]}"; do
        read -r name scene sets <<<"$c"
        # shellcheck disable=SC2086
        target/release/kdmpm run "$scene" $sets --threads "$threads" --out "$out/$name-$i" --quiet
    done
done
python3 - "$out" "$n" "$stream" "${cases[@]}" <<'PY'
import json, statistics, sys
out, n, stream = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
names = [c.split()[0] for c in sys.argv[4:]]
print(f"STREAM triad: {stream:.1f} GB/s")
for name in names:
    runs = [json.load(open(f"{out}/{name}-{i}/summary.json")) for i in range(1, n + 1)]
    points, steps = runs[0]["particles"], runs[0]["steps"]
    print(f"\n{name}: {points} points, {steps} steps")
    print(f"{'system':20s} {'B/point':>8s} {'ns/point':>9s} {'GB/s':>6s} {'of triad':>9s}")
    total_b = total_s = other_s = 0.0
    for k, t in enumerate(runs[0]["systems"]):
        sec = statistics.median(r["systems"][k]["seconds"] for r in runs)
        per = sec / t["calls"] / points * 1e9
        b = t.get("bytes")
        if b is None:
            other_s += sec
            if per >= 0.05:
                print(f"{t['name']:20s} {'-':>8s} {per:9.2f}")
            continue
        bp = (b["read"] + b["written"]) / t["calls"] / points
        total_b += bp
        total_s += sec
        if bp == 0 and per < 0.05:
            continue
        rate = bp / per if per > 0 else 0.0
        print(f"{t['name']:20s} {bp:8.0f} {per:9.2f} {rate:6.1f} {100 * rate / stream:8.0f} %")
    per = total_s / steps / points * 1e9
    rate = total_b / per
    print(f"{'counted':20s} {total_b:8.0f} {per:9.2f} {rate:6.1f} {100 * rate / stream:8.0f} %")
    print(f"bound at the triad: {stream / total_b * 1e3:.1f} M particle-steps/s; "
          f"measured {1e3 / (per + other_s / steps / points * 1e9):.1f} (every system)")
PY
