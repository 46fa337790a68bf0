"""The README agrees with the code and with CI."""

import re
from pathlib import Path

from crane_fmu.cli import main

ROOT = Path(__file__).resolve().parent.parent


def test_readme_variable_tables_are_generated_from_the_tables(capsys):
    main(["info", "--markdown"])
    generated = capsys.readouterr().out.strip()
    readme = (ROOT / "README.md").read_text()
    section = re.search(r"<!-- variables:start -->\n(.*)\n<!-- variables:end -->", readme, re.S).group(1)
    assert section.strip() == generated


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    command = re.search(r"## Run the tests\n\n```\n(.*?)\n```", readme, re.S).group(1)
    assert command in (ROOT / ".ci" / "run").read_text()
