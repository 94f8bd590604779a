"""Measurements the stress tests report beside pass/fail (leak counts, Embree's leak rate):
collected in REPORT by the tests and printed in pytest's terminal summary."""

REPORT: list = []


def pytest_terminal_summary(terminalreporter):
    if REPORT:
        terminalreporter.section("stress suite measurements")
        for line in REPORT:
            terminalreporter.write_line(line)
