"""README table regeneration (tests/bench/readme.py): only the Benchmarks section changes."""
import pytest

from tests.bench import readme

DOC = """# Title

intro

## Benchmarks

Hand-written text.

## Layout

| a | b |
"""


def test_block_is_appended_inside_the_section_then_replaced_in_place():
    once = readme.replace_block(DOC, "errortime", "| x |\n|---|\n| 1 |")
    begin, end = readme.markers("errortime")
    assert once.index("Hand-written text.") < once.index(begin) < once.index(end) \
        < once.index("## Layout")
    assert once.startswith("# Title\n\nintro\n\n## Benchmarks\n\nHand-written text.\n")
    assert once.endswith("## Layout\n\n| a | b |\n")
    twice = readme.replace_block(once, "errortime", "| y |")
    assert "| 1 |" not in twice and "| y |" in twice
    assert twice.count(begin) == 1
    # same body again: unchanged text
    assert readme.replace_block(twice, "errortime", "| y |") == twice
    # a second block leaves the first alone
    both = readme.replace_block(twice, "scaling", "S")
    assert "| y |" in both and both.index(begin) < both.index(readme.markers("scaling")[0])


def test_section_at_the_end_of_the_file():
    text = "# T\n\n## Benchmarks\n\nold\n"
    out = readme.replace_block(text, "partition", "P")
    assert out == "# T\n\n## Benchmarks\n\nold\n\n<!-- bench:partition:begin -->\nP\n" \
                  "<!-- bench:partition:end -->\n"


def test_bad_readmes_are_refused_with_a_reason():
    with pytest.raises(ValueError, match="no '## Benchmarks' section"):
        readme.replace_block("# T\n", "x", "y")
    begin, _ = readme.markers("x")
    with pytest.raises(ValueError, match="only one of the markers"):
        readme.replace_block(DOC.replace("Hand-written text.", begin), "x", "y")
    with pytest.raises(ValueError, match="lowercase"):
        readme.markers("Bad Name")


def test_markers_outside_the_section_are_not_touched():
    begin, end = readme.markers("x")
    text = DOC + f"\n{begin}\nkeep\n{end}\n"
    out = readme.replace_block(text, "x", "new")
    assert out.endswith(f"{begin}\nkeep\n{end}\n")
    assert out.count(begin) == 2


def test_markdown_table_escapes_pipes():
    t = readme.markdown_table(["a", "b"], [[1, "x|y"]])
    assert t.splitlines() == ["| a | b |", "|---|---|", "| 1 | x\\|y |"]


def test_update_writes_the_file(tmp_path):
    p = tmp_path / "README.md"
    p.write_text(DOC)
    readme.update("tracer", "T", p)
    assert "<!-- bench:tracer:begin -->\nT\n<!-- bench:tracer:end -->" in p.read_text()
