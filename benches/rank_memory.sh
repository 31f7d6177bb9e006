#!/usr/bin/env bash
# Each MPI rank's peak resident memory against one rank's, for the 1M-point block (or the
# scene given), from summary.json (`peak_memory_bytes`; over ranks
# `ranks.peak_memory_bytes`, set-up included), with the answer each run gives (kinetic
# energy after the steps), as in docs/performance.md.
#   benches/rank_memory.sh [RANKS] [SCENE] [STEPS] [SPLIT]   (SPLIT: e.g. 2x2, `--split`)
set -euo pipefail
cd "$(dirname "$0")/.."
ranks=${1:-4}
scene=${2:-scenes/block_1m.ron}
steps=${3:-10}
split=()
if [[ -n "${4:-}" ]]; then split=(--split "$4"); fi
cargo build --release --quiet --features mpi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
set_steps=(--set "solver.max_steps=$steps")
target/release/kdmpm run "$scene" --threads 1 --quiet --out "$out/one" "${set_steps[@]}"
mpirun --allow-run-as-root --oversubscribe -n "$ranks" \
    target/release/kdmpm run "$scene" --threads 1 --quiet --out "$out/ranks" "${set_steps[@]}" "${split[@]}"
python3 - "$out" "$ranks" <<'PY'
import json, sys
out, ranks = sys.argv[1], int(sys.argv[2])
one = json.load(open(f"{out}/one/summary.json"))
many = json.load(open(f"{out}/ranks/summary.json"))
base = one["peak_memory_bytes"]
print(f"1 rank: {base / 2**20:.1f} MiB, {one['particles']} points, kinetic energy {one['kinetic_energy']!r}")
for r, (peak, pts) in enumerate(zip(many["ranks"]["peak_memory_bytes"], many["ranks"]["points"])):
    print(f"rank {r} of {ranks}: {peak / 2**20:.1f} MiB ({100 * peak / base:.1f} %), {pts} points")
print(f"kinetic energy over {ranks} ranks {many['kinetic_energy']!r}, laid {many['ranks']['split']}, "
      f"{many['ranks']['bytes_per_step']:.0f} B sent a step")
PY
