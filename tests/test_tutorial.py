"""docs/tutorial.md runs: its Python blocks, in order, in one namespace, as a reader would paste them."""

from __future__ import annotations

import re
from pathlib import Path

TUTORIAL = Path(__file__).resolve().parents[1] / "docs" / "tutorial.md"


def python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_the_tutorial_has_its_examples():
    assert len(python_blocks(TUTORIAL.read_text())) >= 5


def test_every_block_of_the_tutorial_runs_and_its_checks_hold(capsys):
    namespace: dict = {}
    for i, block in enumerate(python_blocks(TUTORIAL.read_text())):
        exec(compile(block, f"{TUTORIAL.name}, block {i + 1}", "exec"), namespace)  # noqa: S102 (the docs' own code)
    printed = capsys.readouterr().out
    assert "bare: peak roof displacement" in printed and "TMD: peak roof" in printed
