#!/usr/bin/env bash
# Tracking benchmark on synthetic ToF sequences made from the shared mocap clips.
#
#   tools/benchmark.sh [DATA_DIR] [OUT_DIR]     (defaults: ../shared/data, benchmark-output)
#
# 1. synthesize one sequence per motion (SR4000 camera, ToF noise, 25 fps): the clips in
#    DATA/motions/*.bvh whole, and ~10 s of the long CMU clip DATA/cmu/126_01.bvh;
# 2. evaluate hc, ep and hc+ep with the smoothed likelihood   -> OUT/report/
# 3. evaluate hc+ep with the pixel-wise likelihood            -> OUT/report-pixel/
# 4. the paper's likelihood comparison of the two hc+ep runs     -> OUT/likelihood.md
# The --json summaries land in OUT/report.json and OUT/report-pixel.json.
set -euo pipefail

DATA=${1:-../shared/data}
OUT=${2:-benchmark-output}
DEPTHTRACK=${DEPTHTRACK:-.venv/bin/depthtrack}
SYNTH=(--camera sr4000 --noise tof --fps 25 --quiet)

if [ ! -d "$DATA/motions" ]; then
  echo "benchmark: $DATA/motions: no such directory (the shared mocap data)" >&2
  exit 2
fi
mkdir -p "$OUT/sequences"

sequences=()
for motion in "$DATA"/motions/*.bvh; do
  name=$(basename "$motion" .bvh)
  echo "synth $name" >&2
  "$DEPTHTRACK" synth "$motion" "$OUT/sequences/$name" "${SYNTH[@]}"
  sequences+=("$OUT/sequences/$name")
done
if [ -f "$DATA/cmu/126_01.bvh" ]; then
  echo "synth cmu_126_01 (10 s)" >&2
  "$DEPTHTRACK" synth "$DATA/cmu/126_01.bvh" "$OUT/sequences/cmu_126_01" --seconds 10 "${SYNTH[@]}"
  sequences+=("$OUT/sequences/cmu_126_01")
fi

echo "eval hc, ep, hc+ep (smoothed likelihood)" >&2
"$DEPTHTRACK" eval "${sequences[@]}" --methods hc,ep,hc+ep --likelihood smoothed \
  --report "$OUT/report" --json > "$OUT/report.json"

echo "eval hc+ep (pixel likelihood)" >&2
"$DEPTHTRACK" eval "${sequences[@]}" --methods hc+ep --likelihood pixel \
  --report "$OUT/report-pixel" --json > "$OUT/report-pixel.json"

# The paper's likelihood comparison: hc+ep's average error with each likelihood, over
# sequences (each weighing the same) and over all frames (frame-weighted, as the paper).
"$(dirname "$DEPTHTRACK")/python" - "$OUT/report.json" "$OUT/report-pixel.json" > "$OUT/likelihood.md" <<'PY'
import json, sys
smoothed, pixel = (json.load(open(p)) for p in sys.argv[1:3])
def frame_weighted(report, key):
    rows = [m["hc+ep"] for m in report["sequences"].values() if m["hc+ep"].get(key) is not None]
    return sum(r[key] * r["frames"] for r in rows) / sum(r["frames"] for r in rows) if rows else None
print("# Likelihood comparison (hc+ep)\n")
print("| metric | smoothed (cm) | pixel (cm) | change with smoothing |")
print("|---|---:|---:|---:|")
for key in ("mean_error_m", "max_error_m", "marker_mean_error_m"):
    for label, s, p in ((f"{key}, sequence mean", smoothed["overall"]["hc+ep"][key], pixel["overall"]["hc+ep"][key]),
                        (f"{key}, frame-weighted", frame_weighted(smoothed, key), frame_weighted(pixel, key))):
        if s is None or p is None:
            continue
        print(f"| {label} | {100 * s:.1f} | {100 * p:.1f} | {100 * (s - p) / p:+.0f}% |")
PY
cat "$OUT/likelihood.md"
echo "benchmark: $OUT/report/report.md, $OUT/report-pixel/report.md, $OUT/likelihood.md" >&2
