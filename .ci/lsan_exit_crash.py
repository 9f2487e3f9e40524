#!/usr/bin/env python3
"""Sorts the failures of a sanitizer run of CTest (its Testing/Temporary/LastTest.log).

LeakSanitizer's exit-time tracer has been seen to crash ("Tracer caught signal 11" in
StopTheWorld) after a test had passed, while GL driver threads were still winding down. Such a
failure says nothing about the test, so test.sh runs it once more; any other failure counts.

Prints the names of the tests whose only fault is that crash, one a line, and exits 0 when every
failure is of that kind; otherwise names the other failures on standard error and exits 1.
Usage: lsan_exit_crash.py LastTest.log
"""
import re
import sys

# The tracer's own crash, and what a real fault prints: a sanitizer's report or a failed test.
CRASH = ("Tracer caught signal", "LeakSanitizer has encountered a fatal error")
REAL = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer: detected memory leaks", "runtime error:", "[  FAILED  ]")


def tests(log):
    """(name, output, passed) for each test block of a LastTest.log."""
    for block in re.split(r"\n(?=\d+/\d+ Testing: )", log):
        m = re.match(r"\d+/\d+ Testing: (\S+)", block)
        if not m:
            continue
        out = block.split("\nOutput:\n", 1)[-1].split("<end of output>", 1)[0]
        yield m.group(1), out, "\nTest Passed." in block


def exit_crash_only(out):
    return "[  PASSED  ]" in out and any(c in out for c in CRASH) and not any(r in out for r in REAL)


def main(argv):
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    try:
        log = open(argv[1], encoding="utf-8", errors="replace").read()
    except OSError as e:
        print(f"{argv[1]}: cannot read the test log: {e.strerror}", file=sys.stderr)
        return 2
    crashes, others = [], []
    for name, out, passed in tests(log):
        if not passed:
            (crashes if exit_crash_only(out) else others).append(name)
    for name in others:
        print(f"{name}: failed (not LeakSanitizer's crash at exit)", file=sys.stderr)
    if others or not crashes:
        return 1
    print("\n".join(crashes))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
