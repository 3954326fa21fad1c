"""docs/troubleshooting.md quotes real messages: each ```text block must still be produced by the code.

A message is matched against the string templates of robotdyn's source: every string literal and f-string
(adjacent literals joined, as Python joins them) with at least 12 literal characters, its ``{...}`` fields turned
into wildcards. A quoted message passes when the literal text of the templates found in it covers at least 40 %
of its characters (the rest are the values: names, numbers, paths), so that the sentences saying what is wrong and
what to do still exist in the code. A quoted message whose wording the code no longer has fails here.
"""

from __future__ import annotations

import ast
import re
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "troubleshooting.md"
MIN_LITERAL = 12
MIN_COVERAGE = 0.4


@lru_cache(maxsize=1)
def templates() -> list[tuple[re.Pattern, str]]:
    """(regex, its longest literal part) of every string template in robotdyn's source."""
    out = []
    for path in sorted((ROOT / "robotdyn").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.JoinedStr):
                parts = [v.value if isinstance(v, ast.Constant) else None for v in node.values]
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                parts = [node.value]
            else:
                continue
            literal = sum(len(p) for p in parts if p)
            if literal >= MIN_LITERAL:
                pattern = "".join(f"({re.escape(p)})" if p is not None else ".*?" for p in parts if p != "")
                out.append((re.compile(pattern, re.S), max((p for p in parts if p), key=len)))
    return out


def quoted_messages() -> list[str]:
    text = PAGE.read_text(encoding="utf-8")
    return [m.strip() for m in re.findall(r"```text\n(.*?)```", text, re.S)]


def test_page_quotes_messages():
    assert len(quoted_messages()) >= 10


def coverage(message: str) -> float:
    """Fraction of the message's characters that are literal text of source templates found in it."""
    covered = [False] * len(message)
    for regex, longest in templates():
        if longest not in message:  # cheap filter before the regex
            continue
        for match in regex.finditer(message):
            for g in range(1, (regex.groups or 0) + 1):
                covered[match.start(g):match.end(g)] = [True] * (match.end(g) - match.start(g))
    return sum(covered) / max(len(message), 1)


@pytest.mark.parametrize("message", quoted_messages(), ids=lambda m: m[:40])
def test_quoted_message_exists_in_the_code(message):
    assert "\n" not in message, "one message per block (messages are one line)"
    assert coverage(message) >= MIN_COVERAGE, f"robotdyn's templates no longer produce: {message}"


def test_the_check_can_fail():
    """A reworded message is caught (the check is not vacuous)."""
    assert coverage("the wheel is somewhere strange; please try turning it off and on again") < MIN_COVERAGE
    quoted = quoted_messages()[1]
    assert coverage(quoted.replace("did you mean", "perhaps you meant").replace("no joint named", "missing joint")
                    ) < MIN_COVERAGE
