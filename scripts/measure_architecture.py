"""The figures of issues 15 and 33: long functions and modules, library imports of the front ends, import circles,
the modules at the package's root and the imports of other modules' private names.

    python scripts/measure_architecture.py [--max-function 100] [--max-module 800]

Reads ``src/motorlab`` with ``ast`` (nothing is imported) and prints what exceeds the limits.
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path
from typing import NamedTuple

SRC = Path(__file__).resolve().parents[1] / "src"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports(tree: ast.AST, name: str, is_package: bool, modules: set[str] | None = None) -> set[str]:
    """Modules imported at module level, inside functions or for type checking only (motorlab ones only).

    ``from pkg import name`` depends on the module ``pkg.name`` when it is one (of ``modules``), else on ``pkg``.
    """
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                pkg = name.split(".") if is_package else name.split(".")[:-1]
                pkg = pkg[: len(pkg) - (node.level - 1)]
                base = ".".join([*pkg, base]) if base else ".".join(pkg)
            for a in node.names:
                sub = f"{base}.{a.name}"
                out.add(sub if modules is not None and sub in modules else base)
                if modules is None:
                    out.update((base, sub))
    return {m for m in out if m.startswith(("motorlab", "control.")) or m == "control"}


def private_imports(tree: ast.AST) -> list[str]:
    """``from motorlab.x import _name``: another module's private name (``__version__`` and the like are public)."""
    return [f"{node.module}.{a.name}" for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("motorlab")
            for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]


#: The front ends: the command line, and the browser app that runs it in child processes (its answers
#: are the CLI's own, docs/ui.md). They sit on top of the library; no library module may import them.
FRONT_ENDS = ("motorlab.cli", "motorlab.ui", "motorlab.__main__")

#: Lines of code (docstring left out) of each function over the limit, filled by :func:`measure`.
code_lengths: dict[str, int] = {}


def _is_docstring(node: ast.stmt) -> bool:
    return isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)


def _is_type_checking(node: ast.AST) -> bool:
    """``if TYPE_CHECKING:`` blocks: imports for annotations only, never run."""
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def measure(max_function: int = 100, max_module: int = 800) -> Measures:
    """What exceeds the limits in ``src/motorlab``."""
    files = sorted((SRC / "motorlab").rglob("*.py"))
    modules = {module_name(p): p for p in files}
    long_functions, long_modules, cli_imports, control_imports, private = [], [], [], [], []
    code_lengths.clear()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        text = path.read_text()
        tree = ast.parse(text)
        n_lines = len(text.splitlines())
        if n_lines > max_module:
            long_modules.append((n_lines, name))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = (node.end_lineno or node.lineno) - node.lineno + 1
                if length > max_function:
                    long_functions.append((length, f"{name}.{node.name}"))
                    doc = node.body[0] if node.body and _is_docstring(node.body[0]) else None
                    doc_lines = (doc.end_lineno or doc.lineno) - doc.lineno + 1 if doc else 0
                    code_lengths[f"{name}.{node.name}"] = length - doc_lines
        private.extend(f"{name}: {p}" for p in private_imports(tree))
        deps = set(imports(tree, name, path.name == "__init__.py", set(modules)))
        deps = {m if m in modules else m.rsplit(".", 1)[0] for m in deps}
        if any(m == "control" or m.startswith("control.") for m in deps):
            control_imports.append(name)
        # importing a.b.c runs the packages a and a.b first: those not already running for this module count too
        own = {name.rsplit(".", k)[0] for k in range(1, name.count(".") + 1)}
        own |= {name} if path.name == "__init__.py" else set()
        deps |= {d.rsplit(".", k)[0] for d in deps for k in range(1, d.count(".") + 1)} - own
        graph[name] = {m for m in deps if m in modules and m != name}
        if not name.startswith(FRONT_ENDS) and any(m.startswith(FRONT_ENDS) for m in graph[name]):
            cli_imports.append(name)
    cycles = find_cycles(graph)
    root = sorted(p.name for p in (SRC / "motorlab").glob("*.py"))
    return Measures(long_functions, long_modules, cli_imports, control_imports, cycles, root, private)


class Measures(NamedTuple):
    long_functions: list[tuple[int, str]]
    long_modules: list[tuple[int, str]]
    cli_imports: list[str]
    control_imports: list[str]
    cycles: list[set[str]]
    root_modules: list[str]
    private_imports: list[str]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-function", type=int, default=100)
    ap.add_argument("--max-module", type=int, default=800)
    args = ap.parse_args()
    (long_functions, long_modules, cli_imports, control_imports, cycles, root,
     private) = measure(args.max_function, args.max_module)
    over = sum(1 for n in code_lengths.values() if n > args.max_function)
    print(f"functions over {args.max_function} lines: {len(long_functions)} "
          f"({over} without their docstrings; lines with docstring / without)")
    for n, f in sorted(long_functions, reverse=True):
        print(f"    {n:5d} {code_lengths[f]:5d}  {f}")
    print(f"modules over {args.max_module} lines: {len(long_modules)}")
    for n, m in sorted(long_modules, reverse=True):
        print(f"    {n:5d}  {m}")
    print(f"library modules importing a front end ({', '.join(FRONT_ENDS)}): {len(cli_imports)}")
    for m in cli_imports:
        print(f"    {m}")
    print(f"library modules importing python-control: {len(control_imports)}")
    for m in control_imports:
        print(f"    {m}")
    print(f"import circles (strongly connected groups, type-checking imports and packages included): {len(cycles)}")
    for c in cycles:
        print("    " + " <-> ".join(sorted(c)))
    print(f"modules at the package's root: {len(root)}: {', '.join(root)}")
    print(f"imports of another module's private name: {len(private)}")
    for p in private:
        print(f"    {p}")


def find_cycles(graph: dict[str, set[str]]) -> list[set[str]]:
    """Strongly connected components of more than one module (Tarjan), packages' ``__init__`` included."""
    g = graph
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[set[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in g.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(comp)

    for v in g:
        if v not in index:
            visit(v)
    return out


if __name__ == "__main__":
    main()
