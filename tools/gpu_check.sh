#!/usr/bin/env bash
# The GPU figures of README "On a GPU", on a machine with a GPU driver (EGL picks it):
# the renderer, candidates per second, each sequence tracked one at a time (frames per
# second, time per stage), a profile of the first, and the test suite on that rasteriser.
#
#   bash tools/gpu_check.sh OUT SEQ [SEQ ...]
#
# OUT: a new folder for gl.txt, bench.json, NAME.json (eval --json), timings.json (each
# track's summary timings and counts), profile.out (cProfile of the first SEQ), pytest.txt.
# PYTHON picks the interpreter (default .venv/bin/python, else python3); WORKERS the pytest
# workers (default: the number of cores); TESTS=0 leaves the suite out. Example, the fourth lease (the SR4000 test
# sequences of `tools/benchmark.py --split test --wide --keep-tracks`):
#   bash tools/gpu_check.sh gpu-out benchmark-output/test/sequences/*_c0_s1
set -uo pipefail
if [ $# -lt 2 ]; then
  echo "usage: bash tools/gpu_check.sh OUT SEQ [SEQ ...]" >&2; exit 2
fi
out=$(realpath -m "$1"); shift
seqs=()
for s in "$@"; do seqs+=("$(realpath -m "$s")"); done
set -- "${seqs[@]}"
if [ -e "$out" ]; then
  echo "gpu_check: $out: exists; name a new folder" >&2; exit 2
fi
for s in "$@"; do
  [ -f "$s/sequence.json" ] || { echo "gpu_check: $s: not a sequence folder (no sequence.json)" >&2; exit 2; }
done
cd "$(dirname "$0")/.." || exit 2
py=${PYTHON:-$( [ -x .venv/bin/python ] && echo .venv/bin/python || echo python3 )}
mkdir -p "$out" || exit 2
step() { echo "== $(date +%T) $*" >&2; }
step "renderer"
"$py" -c "from depthtrack.render.context import gl_info; print(gl_info())" | tee "$out/gl.txt"
step "candidates per second"
"$py" -m depthtrack bench --json --quiet --seconds 0.3 > "$out/bench.json"
for s in "$@"; do
  step "tracking $(basename "$s")"
  "$py" -m depthtrack eval "$s" --methods hc+ep --json --quiet --tracks-out "$out/tracks" \
    > "$out/$(basename "$s").json"
done
"$py" - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
keys = ("seconds", "processing_fps", "wall_seconds", "wall_fps", "timings", "counts", "renderer")
rows = {p.split(os.sep)[-3]: {k: json.load(open(p)).get(k) for k in keys}
        for p in sorted(glob.glob(os.path.join(out, "tracks", "*", "hc+ep", "summary.json")))}
json.dump(rows, open(os.path.join(out, "timings.json"), "w"), indent=1)
for name, r in rows.items():
    print(f"{name}: tracking pass {r['processing_fps']:.2f} fps, whole command {r['wall_fps']:.2f} fps")
PY
step "profile of $(basename "$1")"
"$py" -m cProfile -o "$out/profile.out" -m depthtrack eval "$1" --methods hc+ep --json --quiet > /dev/null
[ "${TESTS:-1}" = 0 ] && exit 0
step "test suite"
"$py" -m pytest -q -n "${WORKERS:-$(nproc)}" --dist loadfile -p no:cacheprovider -rfxX > "$out/pytest.txt" 2>&1
tail -3 "$out/pytest.txt"
