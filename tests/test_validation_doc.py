"""docs/validation.md is what docs/validation.py writes (issue 25 item 1), and its table holds
the numbers the cases' sections explain."""

import importlib.util
import re
import sys
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parent.parent / "docs"


def _script():
    spec = importlib.util.spec_from_file_location("validation_script", DOCS / "validation.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass looks its module up there
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def generated():
    return _script().build_text()


def test_the_committed_page_is_the_scripts_output(generated):
    """Regenerate with `python docs/validation.py` after any change of the model or the text."""
    committed = (DOCS / "validation.md").read_text(encoding="utf-8")
    assert committed == generated


def _table(text: str) -> list[list[str]]:
    lines = [line for line in text.splitlines() if line.startswith("| [")]
    return [[cell.strip() for cell in line.strip("|").split("|")] for line in lines]


def test_the_table_has_every_case_with_machine_readable_numbers(generated):
    """Each case of the issue is a row; every number cell is a plain number or 'n/a', and the
    ratio is chain level / published to the table's three digits."""
    rows = _table(generated)
    names = [re.match(r"\[(.*?)\]", row[0]).group(1) for row in rows]
    for case in ("Wuxi", "Ningbo Line 1", "Li & Selig worked example", "Shanghai Line 1"):
        assert any(case in name for name in names), case
    for row in rows:
        published, method, chain, ratio = row[2], row[4], row[5], row[6]
        for cell in (published, method, chain, ratio):
            assert cell == "n/a" or float(cell) > 0
        if "n/a" not in (published, chain):
            assert float(ratio) == pytest.approx(float(chain) / float(published), rel=2e-2)
    wuxi = next(row for row in rows if "Wuxi" in row[0])
    assert float(wuxi[2]) == 13.44  # the published number as read, not rounded
    li_selig = next(row for row in rows if "Li & Selig" in row[0])
    assert li_selig[2] == li_selig[4] == li_selig[5] == "n/a"  # could not be read: no number


def test_every_case_section_has_source_inputs_result_and_the_difference(generated):
    sections = generated.split("\n## ")[1:]
    cases = [s for s in sections if not s.startswith("The soil-parameter sets")]
    assert len(cases) == 4
    for section in cases:
        assert "**Source.**" in section
        if not section.startswith("Li & Selig"):
            assert "**The difference.**" in section and "**This project" in section
