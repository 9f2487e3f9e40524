"""The sanitizer pass's sorting of failures (.ci/lsan_exit_crash.py): only a test that passed and
then lost LeakSanitizer's tracer at exit is run again; a sanitizer's report, a leak, a failed
assertion or a crash of the test itself fails the run."""
import pathlib
import subprocess
import sys

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / ".ci" / "lsan_exit_crash.py"

PASSED = """[ RUN      ] {name}
[       OK ] {name} (5 ms)
[==========] 1 test from 1 test suite ran. (5 ms total)
[  PASSED  ] 1 test.
"""
TRACER = """Tracer caught signal 11: addr=0x0 pc=0x7f00 sp=0x7f00
==123==LeakSanitizer has encountered a fatal error.
"""


def block(i, name, output, passed):
    return (f"{i}/9 Testing: {name}\n{i}/9 Test: {name}\nCommand: \"test\"\nOutput:\n"
            f"----------------------------------------------------------\n{output}<end of output>\n"
            f"Test time =   1.00 sec\n----------------------------------------------------------\n"
            f"Test {'Passed' if passed else 'Failed'}.\n\"{name}\" end time: Nov 29 04:03 UTC\n\n")


def run(tmp_path, *blocks):
    log = tmp_path / "LastTest.log"
    log.write_text("Start testing: Nov 29 04:00 UTC\n----------------------------------------------------------\n" + "".join(blocks))
    return subprocess.run([sys.executable, str(SCRIPT), str(log)], capture_output=True, text=True)


def test_a_tracer_crash_after_a_pass_is_named_for_a_rerun(tmp_path):
    r = run(tmp_path, block(1, "A.Passes", PASSED.format(name="A.Passes"), True),
            block(2, "B.Crashes", PASSED.format(name="B.Crashes") + TRACER, False),
            block(3, "C.Crashes", PASSED.format(name="C.Crashes") + TRACER, False))
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["B.Crashes", "C.Crashes"]


def test_any_other_failure_fails_the_run_and_is_named(tmp_path):
    for name, output in [
        ("Asan.UseAfterFree", "[ RUN      ] x\n==1==ERROR: AddressSanitizer: heap-use-after-free on address 0x1\n"),
        ("Lsan.Leak", PASSED.format(name="x") + "==1==ERROR: LeakSanitizer: detected memory leaks\n" + TRACER),
        ("Ubsan.Overflow", "core/x.cpp:3:5: runtime error: signed integer overflow\n" + PASSED.format(name="x")),
        ("Gtest.Assertion", "[ RUN      ] x\nx.cpp:1: Failure\n[  FAILED  ] 1 test, listed below:\n"),
        ("Test.Segfault", "[ RUN      ] x\n"),
        ("Tracer.BeforeThePass", "[ RUN      ] x\n" + TRACER),
    ]:
        r = run(tmp_path, block(1, "B.Crashes", PASSED.format(name="B.Crashes") + TRACER, False), block(2, name, output, False))
        assert r.returncode == 1, name
        assert name in r.stderr and "B.Crashes" not in r.stderr, r.stderr


def test_a_run_without_failed_tests_is_not_a_crash(tmp_path):
    r = run(tmp_path, block(1, "A.Passes", PASSED.format(name="A.Passes"), True))
    assert r.returncode == 1
    assert r.stdout == ""


def test_a_missing_log_is_named(tmp_path):
    r = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path / "missing.log")], capture_output=True, text=True)
    assert r.returncode == 2
    assert "missing.log: cannot read the test log" in r.stderr
