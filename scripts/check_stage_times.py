#!/usr/bin/env python3
"""Prints the stage times of scripts/run_tests.sh and checks them: every expected stage ran once and passed,
and the stages add up to the whole run (so no stage went untimed or was skipped).
Usage: check_stage_times.py STAGE_TIMES_TSV TOTAL_SECONDS"""
import sys

EXPECTED = ["setup", "release build", "release tests + quick benchmark", "quoted figures", "include layers", "layout",
            "API reference", "pictures", "sanitized build", "sanitized tests", "fuzz build", "fuzz runs"]
SLACK_SECONDS = 3.0      # the script's own glue between stages
BUDGET_SECONDS = 25 * 60  # on a fresh clone with the compiler cache off (doc/build_time.md)


def main(path, total):
    rows = []
    with open(path) as f:
        for line in f:
            name, seconds, status = line.rstrip("\n").split("\t")
            rows.append((name, float(seconds), int(status)))
    print("run_tests.sh: stage times")
    for name, seconds, status in rows:
        print(f"  {name:<31} {seconds:8.1f} s  {100 * seconds / total:5.1f} %" + ("" if status == 0 else f"  (exit {status})"))
    stages_sum = sum(seconds for _, seconds, _ in rows)
    print(f"  {'sum of stages':<31} {stages_sum:8.1f} s")
    print(f"  {'whole run':<31} {total:8.1f} s")
    errors = []
    names = [name for name, _, _ in rows]
    for name in EXPECTED:
        if names.count(name) != 1:
            errors.append(f"stage '{name}' ran {names.count(name)} times (expected once)")
    errors += [f"unexpected stage '{name}'" for name in names if name not in EXPECTED]
    errors += [f"stage '{name}' failed (exit {status})" for name, _, status in rows if status != 0]
    if abs(total - stages_sum) > SLACK_SECONDS:
        errors.append(f"the stages add up to {stages_sum:.1f} s but the run took {total:.1f} s: "
                      "some work is not timed as a stage")
    if total > BUDGET_SECONDS:
        print(f"run_tests.sh: warning: {total:.0f} s is over the {BUDGET_SECONDS} s that a fresh clone with the "
              "compiler cache off is meant to take (doc/build_time.md)")
    for e in errors:
        print(f"check_stage_times.py: {e}", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], float(sys.argv[2])))
