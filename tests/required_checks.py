"""A pytest plugin (loaded by conftest.py): in CI a skipped test fails the run, with the skip's reason.

Locally a test may skip when something it needs is missing (a C compiler, one of the CPythons of
this machine kind, libcosim, fmpy in a fresh venv). CI installs everything the test extra names,
so there a skip would hide a check that did not run: with the environment variable ``CI=true``
every skip is reported as a failure that says what was missing.
"""

import os

import pytest


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.skipped and os.environ.get("CI") == "true" and not hasattr(report, "wasxfail"):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        report.outcome = "failed"
        report.longrepr = f"skipped in CI (CI=true), where every check is required: {reason}"
