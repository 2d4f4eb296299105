"""The structure of truss_report (docs/architecture.md): three layers, reading -> judging -> page,
each importing only the layers before it; no import circle between the package's modules; no
import of the package inside a function (the way a circle is held open); functions of at most
100 lines, modules of at most 400. Read from the sources with ast, independently of the imports
Python would resolve."""
import ast
import os
import pathlib

from conftest import POSTPROC

PACKAGE = pathlib.Path(POSTPROC) / "truss_report"
LAYERS = {"reading": 0, "judging": 1, "page": 2}   # cli, argparser and __init__: above all (3)
THIRD_PARTY = {"reading": {"numpy", "h5py", "pandas"},
               "judging": {"numpy", "scipy", "pandas"}}


def module_name(path):
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules():
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def resolve(mod, node):
    """The package-absolute name a `from ... import` / `import` statement names (None: outside)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level == 0:
        return [node.module]
    base = mod.split(".")
    is_pkg = modules()[mod].name == "__init__.py"
    base = base if is_pkg else base[:-1]
    base = base[:len(base) - (node.level - 1)]
    target = ".".join(base + ([node.module] if node.module else []))
    names = [f"{target}.{a.name}" for a in node.names] if not node.module else []
    known = modules()
    return [target] + [n for n in names if n in known]


def imports(mod, path):
    """[(imported module, line, inside a function)] of a module."""
    tree = ast.parse(path.read_text())
    res = []

    def walk(node, in_function):
        for child in ast.iter_child_nodes(node):
            inner = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef))
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                for name in resolve(mod, child):
                    res.append((name, child.lineno, in_function))
            walk(child, inner)
    walk(tree, False)
    return res


def layer(mod):
    parts = mod.split(".")
    return LAYERS.get(parts[1], 3) if len(parts) > 1 else 3


def package_graph():
    known = modules()
    graph = {m: set() for m in known}
    for m, p in known.items():
        for name, _, _ in imports(m, p):
            while name and name not in known and "." in name:
                name = name.rsplit(".", 1)[0]
            if name in known and name != m and not (known[name].name == "__init__.py"
                                                    and m.startswith(name + ".")):
                graph[m].add(name)
    return graph


def cycles(graph):
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, res, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                res.append(sorted(comp))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return res


def test_no_import_circle():
    assert cycles(package_graph()) == []


def test_cycle_finder_finds_a_circle():
    """The finder itself: a -> b -> c -> a is one circle, d alone none."""
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_layers_import_only_the_layers_before_them():
    bad = []
    for m, deps in package_graph().items():
        bad += [f"{m} imports {d}" for d in deps if layer(d) > layer(m)
                or (layer(d) == layer(m) and layer(m) < 3 and m.split(".")[1] != d.split(".")[1])]
    assert bad == []


def test_lower_layers_use_only_their_libraries():
    """reading: numpy, h5py, pandas; judging: numpy, scipy, pandas (and the standard library)."""
    import sys
    bad = []
    for m, p in modules().items():
        if layer(m) > 1:
            continue
        allowed = THIRD_PARTY[m.split(".")[1]]
        for name, line, _ in imports(m, p):
            top = name.split(".")[0]
            if top not in ("truss_report", "__future__") and top not in sys.stdlib_module_names \
                    and top not in allowed:
                bad.append(f"{m}:{line} imports {name}")
    assert bad == []


def test_no_package_import_inside_a_function():
    bad = [f"{m}:{line} imports {name} inside a function" for m, p in modules().items()
           for name, line, inside in imports(m, p) if inside and name.startswith("truss_report")]
    assert bad == []


def function_lengths(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node.name, node.lineno, node.end_lineno - node.lineno + 1


def test_function_and_module_sizes():
    files = list(modules().values()) + [pathlib.Path(POSTPROC) / f for f in ("report.py", "run_figures.py")]
    long_functions = [f"{p.name}:{line} {name} {n} lines" for p in files
                      for name, line, n in function_lengths(p) if n > 100]
    long_modules = [f"{p.name}: {len(p.read_text().splitlines())} lines" for p in files
                    if len(p.read_text().splitlines()) > 400]
    assert long_functions == [] and long_modules == []


def test_scripts_do_not_touch_sys_path():
    """postproc/report.py and run_figures.py import the package beside them as Python does for
    any script (its folder is the first entry of sys.path): no sys.path edits, no private names."""
    for name in ("report.py", "run_figures.py"):
        text = (pathlib.Path(POSTPROC) / name).read_text()
        assert "sys.path" not in text and "import _" not in text and " _text" not in text, name


def test_resolve_relative_imports():
    """resolve() itself: `from ..reading.h5file import text` in truss_report.judging.stats."""
    node = ast.parse("from ..reading.h5file import text").body[0]
    assert resolve("truss_report.judging.stats", node)[0] == "truss_report.reading.h5file"
    assert os.path.basename(str(modules()["truss_report.judging.stats"])) == "stats.py"
