"""The tutorial runs as written: every python block in one session, in order, printing what the
page shows after it, every `amr-twin` line with exit 0, and only the public API imported."""

import contextlib
import io
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

import amr_twin
from amr_twin.model.paths import ROOT

PAGES = sorted((ROOT / "docs" / "tutorial").glob("*.md"))
SET_UP = ("python3 -m venv ", ". .venv/bin/activate", "pip install ")
"""The set-up lines of a shell block, which a test run (already installed) skips."""
_BLOCK = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
_IMPORT = re.compile(
    r"^\s*(?:from (amr_twin[\w.]*) import ([\w, ]+)|import (amr_twin[\w.]*))", re.M
)


def blocks(page: Path) -> list[tuple[str, str]]:
    """``(language, text)`` of each fenced block of ``page``, in order."""
    return _BLOCK.findall(page.read_text())


def private_imports(text: str) -> list[str]:
    """The imports in ``text`` that reach past ``amr_twin.__all__``."""
    found = []
    for module, names, bare in _IMPORT.findall(text):
        if (bare or module) != "amr_twin":
            found.append(bare or module)
        elif module:
            found += [n.strip() for n in names.split(",") if n.strip() not in amr_twin.__all__]
    return found


def run_page(page: Path, cwd: Path) -> int:
    """Run ``page``'s blocks in ``cwd`` (see the module); return how many ran."""
    found = blocks(page)
    namespace: dict = {"__name__": "tutorial"}
    ran = 0
    for i, (language, text) in enumerate(found):
        if language == "python":
            assert private_imports(text) == [], f"{page.name}: {private_imports(text)}"
            out = io.StringIO()
            with contextlib.redirect_stdout(out), contextlib.chdir(cwd):
                exec(compile(text, f"{page.name} block {i}", "exec"), namespace)
            shown = found[i + 1][1] if i + 1 < len(found) and found[i + 1][0] == "text" else None
            if shown is not None:
                assert out.getvalue().strip() == shown.strip(), f"{page.name} block {i} printed"
            ran += 1
        elif language == "sh":
            for line in text.splitlines():
                if line.startswith(SET_UP):
                    continue
                assert line.startswith("amr-twin "), f"{page.name}: not a command: {line}"
                command = [sys.executable, "-m", "amr_twin.cli.main", *shlex.split(line)[1:]]
                done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=300)
                assert done.returncode == 0, f"{line}: exit {done.returncode}: {done.stderr[-500:]}"
                ran += 1
        else:
            assert language == "text", f"{page.name} block {i}: language {language!r}"
    return ran


def test_there_is_a_tutorial():
    assert PAGES, "docs/tutorial/ has no page"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_the_tutorial_runs_as_written(page, tmp_path):
    assert run_page(page, tmp_path) >= 6


def test_a_renamed_api_name_or_a_changed_figure_fails_the_tutorial(tmp_path):
    page = PAGES[0]
    text = page.read_text()
    renamed = tmp_path / "renamed.md"
    renamed.write_text(text.replace("run_command", "run_one_command"))
    with pytest.raises(AssertionError, match="run_one_command"):
        run_page(renamed, tmp_path)
    first = next(t for lang, t in blocks(page) if lang == "text")
    changed = tmp_path / "changed.md"
    changed.write_text(text.replace(first, first.replace(".", ",", 1)))
    with pytest.raises(AssertionError, match="printed"):
        run_page(changed, tmp_path)


def test_deep_imports_are_found():
    assert private_imports("from amr_twin import Twin, load_config\nimport amr_twin\n") == []
    deep = "from amr_twin.model.config import load_config\nfrom amr_twin import Secret\n"
    assert private_imports(deep) == ["amr_twin.model.config", "Secret"]
