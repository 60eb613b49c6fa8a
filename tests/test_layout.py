"""The package layout (issue 19): no import circles, packages by role, tests mirroring them.

The import graph is read from the sources with ``ast`` (module-level and lazy imports
alike), so a circle hidden in a function body counts too.
"""

import ast
import importlib
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = {"amr_twin": ROOT / "amr_twin", "amr_twin.controllers": ROOT / "controllers",
           "amr_twin.sensors": ROOT / "sensors", "amr_twin.experiments": ROOT / "experiments"}
SUBPACKAGES = sorted(p.parent.name for p in (ROOT / "amr_twin").glob("*/__init__.py"))


def _modules() -> dict[str, Path]:
    out = {}
    for package, folder in FOLDERS.items():
        for path in folder.rglob("*.py"):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            if package == "amr_twin" and parts and parts[0] in ("controllers", "sensors", "experiments"):
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
            module = (".".join(base[: len(base) - node.level + 1] + [node.module or ""]).rstrip(".")
                      if node.level else node.module)
            found.add(module)
            found.update(f"{module}.{a.name}" for a in node.names)
    deps = set()
    for target in found:
        while target:  # the longest prefix that is one of ours: a name imported from a module is the module
            if target in modules:
                if target != name:
                    deps.add(target)
                break
            target = target.rpartition(".")[0]
    return deps


def import_circles() -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan), sorted."""
    modules = _modules()
    graph = {m: _imports(m, p, modules) for m, p in modules.items()}
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
        assert doc and len(doc.splitlines()) == 1, f"amr_twin/{name}/__init__.py: one line saying its role"


def test_the_readme_lists_every_package():
    readme = (ROOT / "README.md").read_text()
    built = readme[readme.index("## How it is built"):]
    built = built[: built.index("\n## ", 3)]
    for name in SUBPACKAGES:
        assert re.search(rf"`amr_twin/{name}/`", built), f"README's How it is built lacks amr_twin/{name}/"


def test_tests_mirror_the_packages():
    packages = set(SUBPACKAGES) | {"controllers", "sensors", "experiments"}
    folders = {p.name for p in (ROOT / "tests").iterdir() if p.is_dir() and not p.name.startswith((".", "_"))}
    assert folders <= packages, folders - packages
    loose = sorted(p.name for p in (ROOT / "tests").glob("test_*.py") if p.name != Path(__file__).name)
    assert loose == [], f"tests outside the package folders: {loose}"


def test_the_names_the_readme_shows_import():
    readme = (ROOT / "README.md").read_text()
    shown = re.findall(r"^from (amr_twin[\w.]*) import ([\w, ]+)$", readme, re.M)
    assert len(shown) >= 3
    for module, names in shown:
        mod = importlib.import_module(module)
        for name in names.split(","):
            assert hasattr(mod, name.strip()), f"{module}.{name.strip()}"

