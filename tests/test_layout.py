"""The package layout: no import circles, packages by role, tests mirroring them.

The import graph is read from the sources with ``ast`` (module-level and lazy imports
alike), so a circle hidden in a function body counts too.
"""

import ast
import importlib
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = {
    "amr_twin": ROOT / "amr_twin",
    "amr_twin.controllers": ROOT / "controllers",
    "amr_twin.sensors": ROOT / "sensors",
    "amr_twin.experiments": ROOT / "experiments",
}
SUBPACKAGES = sorted(p.parent.name for p in (ROOT / "amr_twin").glob("*/__init__.py"))
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
"""The README and the docs pages, whose links and shown imports are checked."""


def _modules() -> dict[str, Path]:
    out = {}
    for package, folder in FOLDERS.items():
        for path in folder.rglob("*.py"):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            if (
                package == "amr_twin"
                and parts
                and parts[0] in ("controllers", "sensors", "experiments")
            ):
                continue
            out[".".join([package] + parts)] = path
    return out


def _imports(name: str, path: Path, modules: dict) -> set[str]:
    base = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            module = (
                ".".join(base[: len(base) - node.level + 1] + [node.module or ""]).rstrip(".")
                if node.level
                else node.module
            )
            found.add(module)
            found.update(f"{module}.{a.name}" for a in node.names)
    deps = set()
    for target in found:
        while (
            target
        ):  # the longest prefix that is one of ours: a name imported from a module is the module
            if target in modules:
                if target != name:
                    deps.add(target)
                break
            target = target.rpartition(".")[0]
    return deps


def _loops(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one node (Tarjan), sorted."""
    index, low, stack, on, groups = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(groups)


def _module_graph() -> dict[str, set[str]]:
    modules = _modules()
    return {m: _imports(m, p, modules) for m, p in modules.items()}


def import_circles() -> list[list[str]]:
    """Groups of modules that import each other (module-level and lazy imports), sorted."""
    return _loops(_module_graph())


def _package(module: str) -> str:
    """``amr_twin.sim.loop`` -> ``amr_twin.sim``; ``amr_twin`` (the top level) is a package of its
    own."""
    return ".".join(module.split(".")[:2])


def package_graph() -> dict[str, set[str]]:
    """Package -> the other packages any of its modules imports (module-level or lazily)."""
    graph: dict[str, set[str]] = {}
    for module, deps in _module_graph().items():
        graph.setdefault(_package(module), set()).update(_package(d) for d in deps)
    return {package: deps - {package} for package, deps in graph.items()}


def package_loops() -> set[tuple[str, str]]:
    """``(importer, imported)`` package pairs that close a loop: both in one group of packages that
    import each other."""
    graph = package_graph()
    return {(a, b) for group in _loops(graph) for a in group for b in graph[a] if b in group}


def test_the_ground_floor_imports_no_other_package():
    assert package_graph()["amr_twin.base"] == set()


def test_no_package_imports_one_that_imports_it_back():
    """Packages form layers: base, model, ros, sim, sensors, estimation, controllers, assembly (the
    twin built from them), recording, calibration, then the applications; no import, lazy or not,
    goes back."""
    assert package_loops() == set()


def test_the_package_loop_finder_finds_a_lazy_loop(tmp_path, monkeypatch):
    """A module of base/ importing one of sim/ inside a function, while sim/ imports base/: a loop
    (sim/'s import of ros/, which imports none of them, is on no loop)."""
    pkg = tmp_path / "amr_twin"
    for name, text in {
        "__init__": "",
        "base/__init__": "",
        "sim/__init__": "",
        "ros/__init__": "",
        "base/clock": "def now():\n    from amr_twin.sim.loop import Twin\n",
        "sim/loop": "from amr_twin.base.clock import now\nfrom amr_twin.ros import bus\n",
        "ros/bus": "TOPIC = 'cmd_vel'\n",
    }.items():
        (pkg / f"{name}.py").parent.mkdir(parents=True, exist_ok=True)
        (pkg / f"{name}.py").write_text(text)
    monkeypatch.setitem(FOLDERS, "amr_twin", pkg)
    for other in ("amr_twin.controllers", "amr_twin.sensors", "amr_twin.experiments"):
        monkeypatch.setitem(FOLDERS, other, tmp_path / "none")
    assert package_graph()["amr_twin.base"] == {"amr_twin.sim"}
    assert package_loops() == {("amr_twin.base", "amr_twin.sim"), ("amr_twin.sim", "amr_twin.base")}


def test_no_module_imports_one_that_imports_it_back():
    assert import_circles() == []


def test_the_circle_finder_finds_a_circle(tmp_path, monkeypatch):
    """The check above can fail: two modules importing each other (one lazily) are found."""
    pkg = tmp_path / "amr_twin"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from amr_twin.b import x\n")
    (pkg / "b.py").write_text("def x():\n    from amr_twin import a\n")
    (pkg / "c.py").write_text("from amr_twin import a\n")
    monkeypatch.setitem(FOLDERS, "amr_twin", pkg)
    for other in ("amr_twin.controllers", "amr_twin.sensors", "amr_twin.experiments"):
        monkeypatch.setitem(FOLDERS, other, tmp_path / "none")
    assert import_circles() == [["amr_twin.a", "amr_twin.b"]]


def test_the_top_level_is_small_and_each_package_says_its_role():
    top = sorted(p.name for p in (ROOT / "amr_twin").glob("*.py"))
    assert len(top) <= 12, top
    assert len(SUBPACKAGES) >= 6, SUBPACKAGES
    for name in SUBPACKAGES:
        doc = ast.get_docstring(ast.parse((ROOT / "amr_twin" / name / "__init__.py").read_text()))
        assert doc and len(doc.splitlines()) == 1, (
            f"amr_twin/{name}/__init__.py: one line saying its role"
        )


def test_the_layout_page_lists_every_package():
    """docs/reference/layout.md (how it is built; the README links to it) names every package of
    amr_twin/."""
    layout = next((ROOT / "docs").rglob("layout.md")).read_text()
    for name in SUBPACKAGES:
        assert re.search(rf"`amr_twin/{name}/`", layout), (
            f"docs/reference/layout.md lacks amr_twin/{name}/"
        )


def test_tests_mirror_the_packages():
    packages = set(SUBPACKAGES) | {"controllers", "sensors", "experiments"}
    folders = {
        p.name
        for p in (ROOT / "tests").iterdir()
        if p.is_dir() and not p.name.startswith((".", "_"))
    }
    assert folders <= packages, folders - packages
    loose = sorted(
        p.name
        for p in (ROOT / "tests").glob("test_*.py")
        if p.name not in (Path(__file__).name, "test_api.py")
    )  # test_api: amr_twin/__init__.py
    assert loose == [], f"tests outside the package folders: {loose}"


def test_the_names_the_readme_and_docs_show_import():
    shown = [
        found
        for page in DOCUMENTS
        for found in re.findall(r"^from (amr_twin[\w.]*) import ([\w, ]+)$", page.read_text(), re.M)
    ]
    assert len(shown) >= 5
    for module, names in shown:
        mod = importlib.import_module(module)
        for name in names.split(","):
            assert hasattr(mod, name.strip()), f"{module}.{name.strip()}"


_FENCED = re.compile(r"^```.*?^```", re.M | re.S)
_CODE = re.compile(r"`([^`\n]+)`")
_LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
_REPO_PATH = re.compile(
    r"^(?:docs|models|controllers|experiments|sensors|amr_twin|tests|\.ci)/[\w./-]*$"
)


def broken_links(page: Path) -> list[str]:
    """``page``'s relative markdown links (resolved from its folder) and quoted repository paths
    such as `docs/faults.md` (resolved from the root) that name no file or folder; code blocks are
    skipped."""
    text = _FENCED.sub("", page.read_text())
    broken = []
    for target in _LINK.findall(_CODE.sub("", text)):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue  # a web address or an anchor in the page
        if not (page.parent / target.split("#")[0]).exists():
            broken.append(target)
    return broken + [
        path
        for path in _CODE.findall(text)
        if _REPO_PATH.match(path) and not (ROOT / path).exists()
    ]


def test_every_link_in_the_readme_and_docs_resolves():
    broken = {
        page.relative_to(ROOT).as_posix(): found
        for page in DOCUMENTS
        if (found := broken_links(page))
    }
    assert not broken, broken


def test_the_link_check_finds_a_broken_link(tmp_path):
    (tmp_path / "there.md").write_text("x")
    page = tmp_path / "page.md"
    page.write_text(
        "[ok](there.md) [ok](there.md#part) [web](https://rerun.io) `docs/index.md`\n"
        "[gone](gone.md) ![gone](img/gone.png) `docs/gone.md`\n```\n[in code](nowhere.md)\n```\n"
    )
    assert broken_links(page) == ["gone.md", "img/gone.png", "docs/gone.md"]


def test_the_docs_index_lists_every_page():
    index = (ROOT / "docs" / "index.md").read_text()
    listed = set(re.findall(r"^- \[[^\]]+\]\(([\w/-]+\.md)\): \S", index, re.M))
    docs = ROOT / "docs"
    pages = {p.relative_to(docs).as_posix() for p in docs.rglob("*.md")} - {"index.md"}
    assert pages <= listed, f"docs/index.md lacks {sorted(pages - listed)} (one line each)"


def test_the_readme_stays_a_five_minute_read():
    """Set-up, a first run with its picture, the commands by task, links; figures live in docs/."""
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 130
    assert "<!-- generated: " not in readme
    assert re.search(r"!\[[^\]]+\]\(docs/img/\w+\.png\)", readme)
    assert "](docs/index.md)" in readme


def test_the_readme_set_up_commands_are_what_ci_runs():
    """The README's two set-up commands (install + chapter 5, install + tests) are the ones .ci/run
    proves on a fresh clone: the same venv, the same constrained install, the same test command."""
    readme = (ROOT / "README.md").read_text()
    setup = readme[
        readme.index("## Set up on a fresh machine") : readme.index(
            "\n## ", readme.index("## Set up") + 3
        )
    ]
    commands = re.findall(r"^```\n(.+)\n```$", setup, re.M)
    install = (
        "python3 -m venv .venv && . .venv/bin/activate && pip install -c constraints.txt -e "
        '".[dev]"'
    )
    assert commands == [
        f"{install} && amr-twin experiment chapter5 --out results/chapter5",
        f"{install} && python -m pytest -q",
    ]
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert {"python3 -m venv .venv", ". .venv/bin/activate", "python -m pytest -q"} <= set(ci)
    assert any(line.endswith('install --quiet -c constraints.txt -e ".[dev]"') for line in ci)


MAX_DOCSTRING = 1500
"""Characters a module, class or function docstring may hold (``ast.get_docstring``): what, args,
returns, units and a source; reasons and measurements belong in docs/."""
CODE_FILES = ("*.py", "*.c", "*.h", "*.ino", "*.yaml", "*.launch")
_ISSUE = re.compile(r"\bissues? #?\d+", re.I)


def long_docstrings(paths) -> list[str]:
    """``path:line name (characters)`` of each docstring in ``paths`` over :data:`MAX_DOCSTRING`."""
    found = []
    for path in paths:
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
                doc = ast.get_docstring(node)
                if doc and len(doc) > MAX_DOCSTRING:
                    found.append(
                        f"{path.relative_to(ROOT)}:{getattr(node, 'lineno', 1)} "
                        f"{getattr(node, 'name', '<module>')} ({len(doc)})"
                    )
    return found


def issue_numbers(paths) -> list[str]:
    """``path:line`` of each issue number: "issue" or "issues", a space, maybe ``#``, digits."""
    return [
        f"{path.relative_to(ROOT)}:{n}"
        for path in paths
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if _ISSUE.search(line)
    ]


def _code_files(patterns) -> list[Path]:
    folders = ("amr_twin", "controllers", "sensors", "experiments", "tests", "models", ".ci")
    return sorted(
        p
        for folder in folders
        for pattern in patterns
        for p in (ROOT / folder).rglob(pattern)
        if ".venv" not in p.parts
    )


def test_docstrings_say_what_in_a_few_lines():
    assert long_docstrings(_code_files(("*.py",))) == []


def test_the_docstring_check_finds_a_long_one(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "m.py").write_text(f'"""{"x" * 1500}"""\n\nclass A:\n    """{"y" * 1501}"""\n')
    assert long_docstrings([tmp_path / "m.py"]) == ["m.py:3 A (1501)"]


def test_no_issue_numbers_in_code():
    """History lives in commit messages; code, tests, launch files and parameters cite sources."""
    assert issue_numbers(_code_files(CODE_FILES)) == []


def test_the_issue_number_check_finds_one(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    word = "issue"  # written apart, so that this file passes its own check
    text = f"x = 1  # see {word} 19\ny = 2  # {word}s\n# {word.title()} #8: z\nt{word} 3\n"
    (tmp_path / "a.py").write_text(text)
    assert issue_numbers([tmp_path / "a.py"]) == ["a.py:1", "a.py:3"]


def heading_anchors(page: Path) -> set[str]:
    """The anchors a markdown renderer gives ``page``'s headings (GitHub's rule: lower case, spaces
    to ``-``, punctuation but ``_`` and ``-`` dropped)."""
    return {
        re.sub(r"[^a-z0-9_ -]", "", h.strip().lower()).replace(" ", "-")
        for h in re.findall(r"^#+ (.*)$", _FENCED.sub("", page.read_text()), re.M)
    }


def broken_section_links(paths) -> list[str]:
    """``path: docs/PAGE.md#ANCHOR`` of each link from code to a docs section that PAGE has no
    heading for."""
    found = []
    for path in paths:
        for page, anchor in re.findall(r"(docs/[\w/.-]+\.md)#([\w-]+)", path.read_text()):
            if not (ROOT / page).exists() or anchor not in heading_anchors(ROOT / page):
                found.append(f"{path.relative_to(ROOT)}: {page}#{anchor}")
    return found


def test_code_links_to_docs_sections_resolve():
    """A docstring's "Reasons and measurements: docs/PAGE.md#section" leads to that section."""
    assert broken_section_links(p for p in _code_files(("*.py",)) if p != Path(__file__)) == []


def test_the_section_link_check_finds_a_stale_anchor(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "p.md").write_text(
        "# Page\n\n### amr_twin.estimation.ekf\n\n```\n# not a heading\n```\n"
    )
    (tmp_path / "m.py").write_text(
        '"""See docs/p.md#amr_twinestimationekf and docs/p.md#amr_twincontrollersekf,\n'
        'docs/p.md#not-a-heading, docs/gone.md#page."""\n'
    )
    assert broken_section_links([tmp_path / "m.py"]) == [
        "m.py: docs/p.md#amr_twincontrollersekf",
        "m.py: docs/p.md#not-a-heading",
        "m.py: docs/gone.md#page",
    ]


def test_ruff_passes_with_lines_of_at_most_100_characters():
    """``ruff check`` (pyproject.toml's rules, 100-character lines) and ``ruff format --check``
    pass on the repository."""
    if importlib.util.find_spec("ruff") is None:
        pytest.skip("ruff is not installed (pip install -e '.[dev]')")
    for args in (["check", "--no-cache"], ["format", "--check", "--no-cache"]):
        done = subprocess.run(
            [sys.executable, "-m", "ruff", *args, str(ROOT)],
            capture_output=True,
            text=True,
            cwd=ROOT,
        )
        assert done.returncode == 0, f"ruff {' '.join(args)}:\n{done.stdout[-3000:]}{done.stderr}"
