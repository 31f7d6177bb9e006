#!/usr/bin/env bash
# kdmpm against the independent Taichi MPM of ../shared/peers (taichi_mpm3d.py) on the
# 1M-point elastic block, f64, MUSL and USL, alternating one run of each ROUNDS times
# (default 3) on THREADS threads (default 2). Prints each pair's M particle-steps/s, the
# ratio kdmpm / peer, and the cores the peer's process and others used while it ran (the
# peer's own report): a pair is read only when the others stayed near zero.
#
#   benches/taichi_side_by_side.sh [ROUNDS] [THREADS]
#
# The peer needs Taichi 1.7.4 in the Python named by PEER_PYTHON (default python3;
# `pip install taichi==1.7.4`). PEER names the script if it is not at ../shared/peers.
# Results are in docs/performance.md ("Side by side with the Taichi peer").
set -euo pipefail

rounds=${1:-3}
threads=${2:-2}
root=$(cd "$(dirname "$0")/.." && pwd)
peer=${PEER:-$root/../shared/peers/taichi_mpm3d.py}
py=${PEER_PYTHON:-python3}
[ -f "$peer" ] || { echo "no peer script at $peer (set PEER)" >&2; exit 2; }
"$py" -c "import taichi" 2>/dev/null || { echo "$py has no taichi (pip install taichi==1.7.4, or set PEER_PYTHON)" >&2; exit 2; }

(cd "$root" && cargo build --release --quiet --bin kdmpm)
kdmpm=$root/target/release/kdmpm
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

printf '%-5s %5s %9s %9s %7s %10s %10s\n' scheme round kdmpm peer ratio peer_cores others
for scheme in Musl Usl; do
    lower=$(echo "$scheme" | tr '[:upper:]' '[:lower:]')
    for r in $(seq 1 "$rounds"); do
        rm -rf "$work/k"
        "$kdmpm" run "$root/scenes/block_1m.ron" --threads "$threads" --quiet \
            --set solver.max_steps=30 --set "solver.scheme=$scheme" --out "$work/k"
        rm -f "$work/t.json"
        "$py" "$peer" --size 1M --precision f64 --threads "$threads" --scheme "$lower" \
            --min-time 4 --json "$work/t.json" > "$work/peer.log" 2>&1 \
            || { cat "$work/peer.log" >&2; exit 1; }
        # One row from kdmpm's summary.json and the peer's one-line JSON log.
        python3 - "$work/k/summary.json" "$work/t.json" "$lower" "$r" <<'PY'
import json, sys
k = json.load(open(sys.argv[1]))["particle_steps_per_second"] / 1e6
peer = json.load(open(sys.argv[2]))
t = peer["pstep_per_s"] / 1e6
print(f"{sys.argv[3]:<5} {sys.argv[4]:>5} {k:9.2f} {t:9.2f} {k / t:6.2f}x "
      f"{peer['own_cores']:>10} {peer['foreign_cores']:>10}")
PY
    done
done
