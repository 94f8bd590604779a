"""Regeneration of the README's benchmark tables (`--update-readme` of the benchmarks).

Each benchmark owns one block inside the README's "## Benchmarks" section, delimited by
    <!-- bench:NAME:begin --> ... <!-- bench:NAME:end -->
and replaces only the text between its markers. A block missing from the section is appended at
the section's end. Nothing outside that section is ever touched, so the rest of the README (owned
by other people) stays byte for byte as it was.
"""

from __future__ import annotations

import re
from pathlib import Path

from .scenes import REPO

README = REPO / "README.md"
SECTION = "## Benchmarks"


def markers(name: str) -> tuple[str, str]:
    if not re.fullmatch(r"[a-z0-9_-]+", name):
        raise ValueError(f"README block name {name!r} must be lowercase letters, digits, - or _")
    return f"<!-- bench:{name}:begin -->", f"<!-- bench:{name}:end -->"


def _section_span(text: str) -> tuple[int, int]:
    """[start, end) of the Benchmarks section's body (after its heading line, up to the next
    heading of level 1 or 2, or the end of the text)."""
    m = re.search(r"^" + re.escape(SECTION) + r"[ \t]*$", text, re.M)
    if not m:
        raise ValueError(f"the README has no '{SECTION}' section to hold benchmark tables")
    start = m.end()
    nxt = re.search(r"^#{1,2} ", text[start:], re.M)
    return start, (start + nxt.start()) if nxt else len(text)


def replace_block(text: str, name: str, body: str) -> str:
    """Return `text` with the `name` block of its Benchmarks section holding `body`."""
    begin, end = markers(name)
    s, e = _section_span(text)
    section = text[s:e]
    body = body.strip("\n")
    block = f"{begin}\n{body}\n{end}"
    if section.count(begin) > 1 or section.count(end) > 1:
        raise ValueError(f"the README's benchmark section has block '{name}' more than once")
    if (begin in section) != (end in section):
        raise ValueError(f"the README's benchmark section has only one of the markers of "
                         f"block '{name}'; restore {begin} ... {end}")
    if begin in section:
        i, j = section.index(begin), section.index(end) + len(end)
        if j < i:
            raise ValueError(f"README block '{name}': the end marker comes before the begin")
        section = section[:i] + block + section[j:]
    else:
        trimmed = section.rstrip("\n")
        section = trimmed + "\n\n" + block + "\n" + ("\n" if e < len(text) else "")
    return text[:s] + section + text[e:]


def markdown_table(header: list[str], rows: list[list]) -> str:
    """A GitHub markdown table; cells are str()-ed, pipes escaped."""
    def cell(x):
        return str(x).replace("|", "\\|")
    lines = ["| " + " | ".join(cell(h) for h in header) + " |",
             "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def update(name: str, body: str, path: Path = README) -> Path:
    """Rewrite the README with block `name` = body. Returns the path written."""
    path = Path(path)
    text = path.read_text()
    new = replace_block(text, name, body)
    if new != text:
        path.write_text(new)
    return path
