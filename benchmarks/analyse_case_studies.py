"""``cosleec analyse`` on N-Check's nine case studies, initial and corrected (18 files), all checks.

One file after another on one core, each read as LEGOS reads it (``--legos-compat``), with
the default bound; reports the total, the slowest file, the time per check, and how many
findings are proved and how many hold up to the bound. Targets (issue 13): ``total_s`` <= 45
and no file over 2 s. N-Check's own time on the same files and machine, when recorded in
``tests/data/analysis/ncheck_answers.json``, is shown for reference (it is not re-run: it
takes minutes). The baseline measured in the same run: parse + check of the same files
(``cosleec.lang.analyse_file``, best of 3), which every analysis starts with;
``analysis_over_parse_check`` is the total as a multiple of it.
"""

from __future__ import annotations

import json
import sys
import time

from _common import CORPUS, ROOT, args, report
from cosleec.analysis import CHECKS, Settings, analyse_file
from cosleec.lang import analyse_file as parse_and_check

STUDIES = ("ALMI", "ASPEN", "Autocar", "BSN", "CSI", "DAISY", "gdpr", "dressingAssist", "safescade")
TOTAL_TARGET = 45.0
FILE_TARGET = 2.0


def case_studies() -> list:  # type: ignore[type-arg]
    """The 18 case-study files of the corpus, in a stable order."""
    return sorted(
        f for f in CORPUS.glob("NickF0211__LEGOS-SLEEC__*__*.sleec") if f.name.split("__")[2] in STUDIES
    )


def parse_check_time(files: list) -> float:  # type: ignore[type-arg]
    t = time.perf_counter()
    for f in files:
        parse_and_check(f)
    return time.perf_counter() - t


def main() -> int:
    a = args(__doc__ or "")
    files = case_studies()
    if len(files) != 18:
        print(
            f"analyse_case_studies: expected 18 case-study files in {CORPUS}, found {len(files)}",
            file=sys.stderr,
        )
        return 2
    settings = Settings()
    parse_check = min(parse_check_time(files) for _ in range(3))
    per_file: dict[str, float] = {}
    per_check: dict[str, float] = dict.fromkeys(CHECKS, 0.0)
    proved = bounded = failed = unknown = 0
    t_all = time.perf_counter()
    for f in files:
        t = time.perf_counter()
        r = analyse_file(f, settings, legos_compat=True)
        per_file[f.name] = time.perf_counter() - t
        failed += r.failed
        unknown += len(r.unknown)
        for k, v in r.seconds.items():
            if k in per_check:
                per_check[k] += v
            elif k == "coverage":
                pass
        proved += sum(1 for x in r.findings if x.status == "proved")
        bounded += sum(1 for x in r.findings if x.status != "proved")
    total = time.perf_counter() - t_all
    slowest = max(per_file, key=per_file.__getitem__)
    ncheck = ROOT / "tests" / "data" / "analysis" / "ncheck_answers.json"
    ncheck_total = None
    if ncheck.exists():
        ncheck_total = json.loads(ncheck.read_text(encoding="utf-8")).get("total_s")
    result = {
        "benchmark": "analyse_case_studies",
        "total_s": round(total, 3),
        "parse_check_s": round(parse_check, 4),
        "analysis_over_parse_check": round(total / parse_check, 1),
        "max_file_s": round(per_file[slowest], 3),
        "slowest_file": slowest,
        "per_check_s": {k: round(v, 3) for k, v in per_check.items()},
        "findings_proved": proved,
        "findings_bounded": bounded,
        "files_not_analysed": failed,
        "undecided_or_noted": unknown,  # questions out of time, and notes (priorities, limits)
        "bound": settings.bound,
        "ncheck_total_s_recorded": ncheck_total,
        "meets_targets": total <= TOTAL_TARGET and per_file[slowest] <= FILE_TARGET and not failed,
    }
    rows = [
        ("total", f"{total:.2f} s", f"target <= {TOTAL_TARGET:g} s"),
        (
            "parse + check of the same files",
            f"{parse_check * 1000:.0f} ms",
            f"the analysis is {total / parse_check:.0f}x it (same run)",
        ),
        ("slowest file", f"{per_file[slowest]:.2f} s", f"{slowest} (target <= {FILE_TARGET:g} s)"),
        *[(f"check {k}", f"{v:.2f} s", "") for k, v in per_check.items()],
        (
            "findings",
            f"{proved} proved, {bounded} up to bound {settings.bound}",
            f"{unknown} undecided or noted",
        ),
        (
            "N-Check (recorded)",
            "-" if ncheck_total is None else f"{ncheck_total:.0f} s",
            "same files, all five checks",
        ),
    ]
    report("cosleec analyse: N-Check's 18 case-study files, all checks", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
