"""``roller-gym benchmark``: the work-precision study (:mod:`roller_gym.bench.workprecision`).

    roller-gym benchmark             # measure (~7 min on 2 cores), then render docs/BENCHMARKS.md
    roller-gym benchmark --quick     # a smoke run of every part
    roller-gym benchmark --render    # the page and plots again from the results file, no measuring
    roller-gym benchmark --out DIR   # DIR/benchmarks/workprecision.json, DIR/BENCHMARKS.md, plots

Rendering also writes DIR/MAINTAINERS.md (the targets and verdicts of both studies' results);
the measurement says on stderr which part starts.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from roller_gym.bench import maintainers, records, report
from roller_gym.bench.verdicts import work_precision_verdicts
from roller_gym.scripts.arguments import output_folder, program_parser


def build_parser() -> argparse.ArgumentParser:
    p = program_parser("benchmark", "Speed against error: every integrator against a DOP853 "
                       "reference, MuJoCo and Gymnasium's environments, measured in one run.")
    p.add_argument("--quick", action="store_true", help="a smoke run of every part, in minutes")
    p.add_argument("--render", action="store_true",
                   help="measure nothing: render the page and plots from the results file")
    p.add_argument("--out", type=Path, default=Path("docs"),
                   help="the docs folder: results go to OUT/benchmarks/workprecision.json, the "
                        "page to OUT/BENCHMARKS.md, the plots to OUT/benchmarks (default ./docs)")
    return p


def main(argv: Sequence[str] | None = None) -> None:
    parser = build_parser()
    args = parser.parse_args(argv)
    path = report.results_path(args.out)
    if args.render:
        if args.quick:
            parser.error("--render measures nothing: --quick does not apply")
        if not path.is_file():
            raise SystemExit(f"no results file at {path}: `roller-gym benchmark` measures one")
        try:
            results = records.load_results(path)
            page = report.write(results, args.out)
        except (ValueError, KeyError, TypeError, AttributeError) as error:
            raise SystemExit(f"{path} is not a results file `roller-gym benchmark` wrote "
                             f"({type(error).__name__}: {error}); measure again without "
                             "--render") from None
        print(f"wrote {page}")
    else:
        output_folder(path.parent, "--out")  # before measuring, not after
        from roller_gym.bench import workprecision  # MuJoCo, the environments, the kernels

        command = "roller-gym benchmark" + " --quick" * args.quick + (
            f" --out {args.out}" if args.out != Path("docs") else "")
        results = workprecision.measure(workprecision.Config.make(args.quick), command)
        records.save_results(results, path)
        print(f"wrote {path}")
        print(f"wrote {report.write(results, args.out)}")
    print(f"wrote {maintainers.write(args.out)}")
    for v in work_precision_verdicts(results):
        print(f"{v.sentence.replace('**', '')}: {v.target}: {v.measured}")


if __name__ == "__main__":
    main()
