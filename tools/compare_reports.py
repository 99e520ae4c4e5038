#!/usr/bin/env python3
"""Compare two held-out benchmark runs sequence by sequence (a setting measured on dev).

    .venv/bin/python tools/compare_reports.py BASE/dev/report.json NEW/dev/report.json

Both runs must hold the same sequences (the same split, preset, seeds and motions; the
tracker settings or the commit differ). Prints each sequence's figure in both runs and the
difference, then the mean difference with its standard error, how many sequences lost or
gained more than the threshold, how many did not move, and the mean frame-rate ratios.
``--json`` prints the same for machines (:func:`benchmark_report.paired`).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchmark_report import paired  # noqa: E402

#: Metrics that are fractions: shown in points, a default threshold of 5 points.
FRACTIONS = ("within_10cm", "back_to_front_fraction")


def _load(path: Path) -> dict:
    try:
        report = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SystemExit(f"compare_reports: {path}: cannot read it ({exc.strerror})") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SystemExit(f"compare_reports: {path}: not JSON ({exc})") from None
    if not isinstance(report, dict) or not isinstance(report.get("sequences"), list):
        raise SystemExit(f"compare_reports: {path}: not a report.json of tools/benchmark.py "
                         "(no 'sequences' list)")
    return report


def _fmt(v, scale):
    return "-" if v is None else f"{scale * v:.1f}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n"
               "  tools/compare_reports.py base/dev/report.json new/dev/report.json\n"
               "  tools/compare_reports.py a.json b.json --metric mean_error_m --threshold 0.02 --json")
    parser.add_argument("base", type=Path, help="report.json of the run compared against")
    parser.add_argument("new", type=Path, help="report.json of the run with the change")
    parser.add_argument("--method", default="hc+ep", help="tracking method (default hc+ep)")
    parser.add_argument("--metric", default="within_10cm",
                        help="per-sequence metric of depthtrack eval --json (default within_10cm)")
    parser.add_argument("--threshold", type=float, default=None,
                        help="a sequence lost or gained when it moved by more than this (in the "
                             "metric's units; default 0.05 for fractions, else 0)")
    parser.add_argument("--json", action="store_true", help="print the comparison as JSON")
    args = parser.parse_args(argv)
    try:
        base, new = _load(args.base), _load(args.new)
    except SystemExit as exc:
        print(exc, file=sys.stderr)
        return 2
    fraction = args.metric in FRACTIONS
    threshold = args.threshold if args.threshold is not None else (0.05 if fraction else 0.0)
    result = paired(base, new, args.method, args.metric, threshold)
    if result["n"] == 0:
        print(f"compare_reports: {args.base} and {args.new} share no sequence with "
              f"{args.method} {args.metric}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(result, indent=1))
        return 0
    scale = 100.0 if fraction else 1.0
    unit = " (points)" if scale == 100.0 else ""
    print(f"{'sequence':28s} {'base':>7s} {'new':>7s} {'new-base':>9s}")
    for r in result["rows"]:
        print(f"{r['name']:28s} {_fmt(r['base'], scale):>7s} {_fmt(r['new'], scale):>7s} "
              f"{_fmt(r['difference'], scale):>9s}")
    se = result["standard_error"]
    print(f"\n{args.method} {args.metric}{unit}: mean difference "
          f"{scale * result['mean_difference']:+.2f} ± {'-' if se is None else f'{scale * se:.2f}'} "
          f"(standard error) over {result['n']} sequences; moved by more than "
          f"{scale * threshold:g}: {result['lost']} lost, {result['gained']} gained; "
          f"{result['unchanged']} unchanged")
    ratios = [f"{k} {result[k + '_ratio']:.2f}x" for k in ("fps", "wall_fps")
              if result[k + "_ratio"] is not None]
    if ratios:
        print("mean frame-rate ratio new/base: " + ", ".join(ratios))
    for key in ("only_base", "only_new"):
        if result[key]:
            print(f"in {key.split('_')[1]} alone: {', '.join(result[key])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
