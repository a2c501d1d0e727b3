"""The house: one installed namespace, imports that run one way, no import circles, no giant room.

Read statically (ast), function-level imports included, so a lazy import cannot hide a circle.
"""
import ast
import functools
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from conftest import ROOT

PACKAGES = ("derive", "generated", "verify")
# Rank of each room of verify/: a module may import only from a room of lower rank (or its own room).
RANK = {"errors": 0, "outcomes": 0, "defaults": 0, "options": 0.5, "io": 1, "models": 1, "solve": 2, "proof": 3,
        "workflows": 4, "papers": 5, "cli": 6, "api": 7, "bench": 7, "power": 7, "regenerate": 7, "__main__": 7}


def modules():
    """{dotted name under garant: path} for every module of the three packages."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out["garant." + ".".join(parts)] = path
    return out


@functools.lru_cache(maxsize=None)
def parsed(path):
    """The module's syntax tree, parsed once for every test of this file (none changes it)."""
    return ast.parse(path.read_text())


def _at_import_time(tree):
    """The nodes that run when the module is imported: everything but the bodies of functions."""
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            todo.extend(ast.iter_child_nodes(node))


def imports(name, path, known, at_import=False):
    """Modules of garant that `name` imports anywhere in its text (resolved to known module names), or,
    `at_import`, only where they run when the module is imported (not inside a function)."""
    is_pkg = path.name == "__init__.py"
    here = name.split(".") if is_pkg else name.split(".")[:-1]
    found = set()
    tree = parsed(path)
    for node in (_at_import_time(tree) if at_import else ast.walk(tree)):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = here[:len(here) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            targets = [f"{mod}.{a.name}" for a in node.names] + [mod]
        else:
            continue
        for t in targets:
            while t and t not in known:
                t = t.rpartition(".")[0]
            if t and t != name and not name.startswith(t + "."):
                found.add(t)
    return found


@functools.lru_cache(maxsize=None)
def graph():
    known = modules()
    return {n: imports(n, p, known) for n, p in known.items()}


def test_no_module_imports_a_module_that_imports_it_back():
    g = graph()

    def reach(start):
        seen, todo = set(), list(g[start])
        while todo:
            n = todo.pop()
            if n not in seen:
                seen.add(n)
                todo += g[n]
        return seen
    circles = sorted(n for n in g if n in reach(n))
    assert not circles, f"modules on an import circle: {circles}"


def test_cycle_detector_sees_a_circle(tmp_path):
    # The check above can fail: two modules that import each other are found.
    (tmp_path / "a.py").write_text("from . import b\n")
    (tmp_path / "b.py").write_text("def f():\n    from .a import x\n")
    known = {"garant.p.a": tmp_path / "a.py", "garant.p.b": tmp_path / "b.py"}
    assert imports("garant.p.a", known["garant.p.a"], known) == {"garant.p.b"}
    assert imports("garant.p.b", known["garant.p.b"], known) == {"garant.p.a"}


def test_layers_run_one_way():
    """derive -> generated <- verify; inside verify, cli -> papers -> workflows -> proof -> solve -> io/models
    -> options -> errors."""
    bad = []
    for name, deps in graph().items():
        layer = name.split(".")[1]
        for d in deps:
            other = d.split(".")[1]
            if layer == "derive" and other != "derive" or layer == "generated" and other != "generated":
                bad.append((name, d))
            elif layer == other == "verify":
                room, to = name.split(".")[2], d.split(".")[2]
                if room != to and RANK[to] >= RANK[room]:
                    bad.append((name, d))
    assert not bad, f"imports against the arrows: {bad}"


#: What verify may import from derive when a module is imported: the papers' published figures (plain
#: data) and the (empty) package itself. Everything else of derive (SymPy) only inside the functions that
#: re-derive a model.
DERIVE_AT_IMPORT = {"garant.derive", "garant.derive.published"}


def derive_at_import(known):
    """(verify module, derive module) pairs imported at import time against DERIVE_AT_IMPORT."""
    return sorted((n, d) for n, p in known.items() if n.startswith("garant.verify")
                  for d in imports(n, p, known, at_import=True)
                  if d.startswith("garant.derive") and d not in DERIVE_AT_IMPORT)


def test_verify_reaches_derive_only_inside_functions(tmp_path):
    """docs/architecture.md: `import garant.verify.X` never loads SymPy through derive."""
    assert not derive_at_import(modules())
    # It can fail: a planted module-level import of the generator is found; the same inside a function is not.
    (tmp_path / "top.py").write_text("import numpy\nfrom garant.derive import codegen\n")
    (tmp_path / "lazy.py").write_text("def f():\n    from garant.derive import codegen\n")
    known = {**modules(), "garant.verify.top": tmp_path / "top.py", "garant.verify.lazy": tmp_path / "lazy.py"}
    assert derive_at_import(known) == [("garant.verify.top", "garant.derive.codegen")]


def test_largest_room_under_a_third_of_the_code():
    rooms = {}
    for name, path in modules().items():
        parts = name.split(".")
        room = ".".join(parts[1:3]) if parts[1] == "verify" and (ROOT / "/".join(parts[1:3])).is_dir() else parts[1]
        rooms[room] = rooms.get(room, 0) + len(path.read_text().splitlines())
    total = sum(rooms.values())
    room, size = max(rooms.items(), key=lambda kv: kv[1])
    assert size < total / 3, f"{room} holds {size} of {total} lines"


@pytest.mark.slow
@pytest.mark.skipif(not (ROOT / "pyproject.toml").exists(), reason="needs the source tree")
def test_wheel_installs_only_the_garant_namespace(tmp_path):
    shutil.rmtree(ROOT / "build", ignore_errors=True)      # setuptools' build/ keeps modules since moved away
    out = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                          "-w", str(tmp_path), str(ROOT)], capture_output=True, text=True)
    shutil.rmtree(ROOT / "build", ignore_errors=True)
    assert out.returncode == 0, out.stderr[-2000:]
    (wheel,) = tmp_path.glob("garant-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names}
    assert tops == {"garant", next(t for t in tops if t.endswith(".dist-info"))}, tops
    for must in ("garant/__init__.py", "garant/derive/codegen.py", "garant/derive/stands/two_axis.toml",
                 "garant/derive/templates/model/MODEL.py.jinja", "garant/generated/two_axis.py",
                 "garant/verify/cli/__init__.py", "garant/verify/solve/lp.py",
                 "garant/docs/schemas/calibration.schema.json",
                 "garant/verify/proof/certificates/two-axis_q1.json"):   # what `garant verify` re-checks
        assert must in names
    # the published file schemas are the one part of docs/ the readers use (verify/io/schemas.py)
    assert not any(n.startswith("garant/tests") or (n.startswith("garant/docs") and not n.startswith(
        "garant/docs/schemas/")) for n in names)
    # developer tools run from a checkout (python -m verify.bench, python -m verify.power), not installed
    assert not any(n.startswith(("garant/verify/bench", "garant/verify/power", "garant/verify/baseline"))
                   for n in names), [n for n in names if "bench" in n or "power" in n]


def test_import_garant_is_light_and_gives_the_api():
    code = ("import sys, garant; assert 'sympy' not in sys.modules and 'cvxpy' not in sys.modules; "
            "print(sorted(garant.__all__)); print(garant.load_model('two-axis').Q_NAMES[0])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd="/")
    assert out.returncode == 0, out.stderr
    assert "estimate" in out.stdout and out.stdout.strip().endswith("q1")


def test_the_command_uses_one_blas_thread_unless_told_otherwise():
    # The command's thin least-squares fits cost about twice the CPU with threaded BLAS. The
    # command module sets one thread before numpy loads (numpy must not be loaded by then, or the setting
    # is too late); a user's own setting wins.
    import os
    code = ("import sys, os, garant.verify.cli; assert 'numpy' not in sys.modules; "
            "print(os.environ['OPENBLAS_NUM_THREADS'], os.environ['OMP_NUM_THREADS'])")
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd="/", env=env)
    assert out.returncode == 0 and out.stdout.split() == ["1", "1"], out.stderr
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd="/",
                         env={**env, "OPENBLAS_NUM_THREADS": "2"})
    assert out.stdout.split() == ["2", "1"], out.stderr


def test_architecture_lists_every_module():
    """docs/architecture.md names every module of the three packages (an empty __init__ aside)."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    missing = [str(p.relative_to(ROOT)) for p in modules().values()
               if p.read_text().strip() and f"`{p.relative_to(ROOT)}`" not in text]
    assert not missing, f"modules docs/architecture.md does not list: {missing}"


def test_project_cites_the_papers_not_files_outside_it():
    # Users get the repository: its code, docs and generated files cite 000, 001 and 003 by equation,
    # never the notes they were built from. A docstring citing "SPEC.md" (as rotations.py did) fails here.
    # (Example commands may name the real recordings beside the clone: those are data, cited by paper.)
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True).stdout.split()
    if not tracked:
        pytest.skip("not a git checkout")
    bad = [f for f in tracked if f.endswith((".py", ".md", ".jinja", ".toml")) and f != "tests/cli/test_layout.py"
           and any(s in (ROOT / f).read_text(errors="replace") for s in ("SPEC.md", "STYLE.md"))]
    assert not bad, f"cite the papers, not outside files: {bad}"


def test_only_commands_print_and_only_io_plots():
    # Workflows compute and return results; the commands (cli/) print them and io/ writes and plots them,
    # so the API (which calls the same workflows) never prints. A print() or a matplotlib import planted in
    # a workflow (as identify.print_report and calibrate_norm.plot were) fails here. Developer tools and
    # `if __name__ == "__main__"` blocks and the `python -m` entry points aside.
    allowed = ("verify/cli/", "verify/io/", "verify/bench/", "verify/power/", "derive/__main__.py",
               "verify/proof/__main__.py", "verify/regenerate.py")
    bad = []
    for name, path in modules().items():
        rel = str(path.relative_to(ROOT))
        if rel.startswith(allowed):
            continue
        tree = parsed(path)
        main_blocks = {id(n) for node in tree.body if isinstance(node, ast.If) and "__main__" in ast.unparse(node.test)
                       for n in ast.walk(node)}
        for node in ast.walk(tree):
            if id(node) in main_blocks:
                continue
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "print":
                bad.append(f"{rel}:{node.lineno} print")
            if isinstance(node, (ast.Import, ast.ImportFrom)) and "matplotlib" in ast.unparse(node):
                bad.append(f"{rel}:{node.lineno} matplotlib")
    assert not bad, bad


def test_every_public_definition_has_a_docstring():
    # derive/, verify/ and generated/: a public function, class or method without a docstring fails here
    # (141 of 494 had none).
    missing = []
    for name, path in modules().items():
        tree = parsed(path)
        for node in tree.body:
            for it in [node] + (node.body if isinstance(node, ast.ClassDef) else []):
                if isinstance(it, (ast.FunctionDef, ast.ClassDef)) and not it.name.startswith("_") \
                        and not ast.get_docstring(it):
                    missing.append(f"{path.relative_to(ROOT)}:{it.lineno} {it.name}")
    assert not missing, missing


def test_ruff_finds_nothing():
    """`ruff check` with pyproject's [tool.ruff] (pycodestyle, pyflakes, numpy-convention docstrings, 120
    columns) is clean. Red on a line of 121 characters, an unused import or a function without a docstring."""
    ruff = Path(sys.executable).with_name("ruff")
    assert ruff.exists(), "ruff is in the test extra (pip install -e '.[test]')"
    r = subprocess.run([str(ruff), "check", "--no-cache", "--output-format", "concise", str(ROOT)], capture_output=True,
                       text=True, cwd=ROOT)
    assert r.returncode == 0, r.stdout[-3000:]


def test_the_bench_runs_its_subprocesses_from_the_repository():
    """python -m verify.bench times `python -m derive --check` in a subprocess from bench.ROOT: that must be the
    repository (red as it was when the bench moved into verify/bench/ and ROOT stayed one level short: the
    subprocess found no module derive and the bench stopped on its first figure)."""
    from garant.verify import bench
    from garant.verify.bench import peer
    assert (bench.ROOT / "derive" / "__main__.py").is_file() and bench.ROOT == ROOT
    assert peer.ROOT == ROOT


@pytest.mark.slow
def test_one_command_regenerates_everything_derived_and_checks_it():
    """`python -m verify.regenerate --check`: the generated modules, the certificates, docs/cli.md, docs/fields.md
    and the module table of docs/architecture.md are as a fresh rendering makes them. The table was kept by hand and
    39 of its 131 rows had drifted from their module's docstring; a stale or missing row is rewritten."""
    from garant.verify import regenerate
    assert regenerate.main(["--check"]) == 0
    text = (ROOT / "docs" / "architecture.md").read_text()
    broken = text.replace("| `verify/outcomes.py` |", "| `verify/outcomes.py` | drifted |", 1)
    broken = broken.replace(next(line for line in text.splitlines() if line.startswith("| `verify/errors.py`")) + "\n",
                            "", 1)
    assert broken != text and regenerate.module_table(broken) == text
