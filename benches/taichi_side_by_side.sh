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

# A field of a JSON file (summary.json), or of its last line (the peer's --json log).
field() {
    python3 -c "import json, sys
text = open(sys.argv[1]).read()
try:
    doc = json.loads(text)
except ValueError:
    doc = json.loads(text.splitlines()[-1])
print(doc[sys.argv[2]])" "$@"
}

printf '%-5s %5s %9s %9s %7s %10s %10s\n' scheme round kdmpm peer ratio peer_cores others
for scheme in Musl Usl; do
    lower=$(echo "$scheme" | tr '[:upper:]' '[:lower:]')
    for r in $(seq 1 "$rounds"); do
        rm -rf "$work/k"
        "$kdmpm" run "$root/scenes/block_1m.ron" --threads "$threads" --quiet \
            --set solver.max_steps=30 --set "solver.scheme=$scheme" --out "$work/k"
        k=$(field "$work/k/summary.json" particle_steps_per_second)
        rm -f "$work/t.json"
        "$py" "$peer" --size 1M --precision f64 --threads "$threads" --scheme "$lower" \
            --min-time 4 --json "$work/t.json" > "$work/peer.log" 2>&1 \
            || { cat "$work/peer.log" >&2; exit 1; }
        t=$(field "$work/t.json" pstep_per_s)
        own=$(field "$work/t.json" own_cores)
        others=$(field "$work/t.json" foreign_cores)
        python3 -c "import sys; k, t = float(sys.argv[1]) / 1e6, float(sys.argv[2]) / 1e6; \
print(f'{sys.argv[3]:<5} {sys.argv[4]:>5} {k:9.2f} {t:9.2f} {k / t:6.2f}x {sys.argv[5]:>10} {sys.argv[6]:>10}')" \
            "$k" "$t" "$lower" "$r" "$own" "$others"
    done
done
