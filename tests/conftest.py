"""Hypothesis profiles.

``make test`` (and CI) run the property tests derandomized: the same examples on every run
for a given Hypothesis version and test, so a red run is reproducible and main does not turn
red by luck. ``make fuzz`` (HYPOTHESIS_PROFILE=explore) runs them again and again with new
random examples; whatever it finds becomes a plain regression test. Neither profile has a
deadline: timing is for bench/, and a loaded 2-core CI machine must not fail a property.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile("repeatable", derandomize=True, database=None, deadline=None,
                          print_blob=True)
settings.register_profile("explore", deadline=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))

# every Data Bus in the tests (and in the processes they start) checks each record's type
# against its declaration in backend.topics
os.environ["TOUCHLINE_CHECK_TOPICS"] = "1"


# ---- suites that did not run: said loudly, and fatal under CI ------------------------------
#
# A green run must not hide that the Octave engine or the multicast (real sockets) tests were
# skipped (Octave missing, loopback multicast not set up without root). Every skip is listed by
# reason at the end of the run and written to test-results/pytest-skipped.txt for `make test`'s
# closing summary; with CI set (CI runs .ci/run with CI=true) a skip of a required suite is a
# failure.

import pathlib  # noqa: E402

import pytest  # noqa: E402

#: a skip whose reason mentions one of these is a failure under CI
REQUIRED_SUITES = ("octave", "multicast")
_SKIPS: dict[str, list[str]] = {}


def _ci() -> bool:
    return os.environ.get("CI", "").lower() in ("1", "true", "yes")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]):  # type: ignore[no-untyped-def]
    outcome = yield
    report = outcome.get_result()
    if not report.skipped or not isinstance(report.longrepr, tuple):
        return
    reason = str(report.longrepr[2]).removeprefix("Skipped: ")
    _SKIPS.setdefault(reason, []).append(item.nodeid)
    if _ci() and any(k in reason.lower() for k in REQUIRED_SUITES):
        report.outcome = "failed"
        report.longrepr = (f"{item.nodeid} was skipped under CI, which must run it: {reason}")


def pytest_terminal_summary(terminalreporter):  # type: ignore[no-untyped-def]
    lines = [f"{len(ids)} test(s) did not run: {reason}" for reason, ids in sorted(_SKIPS.items())]
    out = pathlib.Path(__file__).resolve().parents[1] / "test-results"
    out.mkdir(exist_ok=True)
    (out / "pytest-skipped.txt").write_text("".join(f"{ln}\n" for ln in lines))
    if lines:
        terminalreporter.section("SUITES THAT DID NOT RUN", sep="!", red=True, bold=True)
        for ln in lines:
            terminalreporter.line(ln, red=True)
