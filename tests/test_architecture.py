"""The house shows the scales: the import graph of ``src/nmmm``, read from the source with ``ast``.

- every package imports only from packages before it in :data:`FLOORS` (data flows down the scales);
- no cycle between modules (imports inside functions count: a deferred import that closes a circle is
  still a circle);
- no module above :data:`MAX_LINES` lines (one module per concept).
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
ROOT = SRC / "nmmm"

#: the floors, bottom first: a module may import from its own floor and the floors below it
FLOORS = ("_tbb_runtime", "errors", "spectra", "atomic_io", "html_repr", "cluster", "colour", "materials", "ema", "microstructure", "homogenize", "layers",
          "ellipsometry", "appearance", "experiment", "recipes", "matching", "demo", "cli")
MAX_LINES = 800


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


MODULES = {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _resolve(name: str) -> str | None:
    """The longest prefix of a dotted name that is a module of nmmm."""
    parts = name.split(".")
    while parts:
        candidate = ".".join(parts)
        if candidate in MODULES:
            return candidate
        parts.pop()
    return None


def _imports(module: str) -> set[str]:
    """nmmm modules imported by ``module`` anywhere in its source (top level or inside functions)."""
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    package = module if _is_package(module) else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                prefix = ".".join(base + ([node.module] if node.module else []))
            else:
                prefix = node.module or ""
            # `from pkg import sub` imports the submodule `pkg.sub`; `from pkg import name` imports pkg
            targets = [f"{prefix}.{a.name}" for a in node.names]
        else:
            continue
        for target in targets:
            if target.split(".")[0] != "nmmm":
                continue
            resolved = _resolve(target)
            if resolved and resolved != module:
                found.add(resolved)
    return found


GRAPH = {m: _imports(m) for m in MODULES}


def _floor(module: str) -> int | None:
    """Index in FLOORS of a module's top-level package; None for ``nmmm`` and ``nmmm.__main__``."""
    parts = module.split(".")
    if len(parts) < 2:
        return None
    top = parts[1]
    if top == "__main__":
        return FLOORS.index("cli")
    return FLOORS.index(top) if top in FLOORS else -1


def test_every_top_level_module_has_a_floor():
    unknown = sorted({m.split(".")[1] for m in MODULES if _floor(m) == -1})
    assert not unknown, f"top-level modules/packages not in FLOORS {FLOORS}: {unknown}"


def test_imports_only_flow_down_the_floors():
    upward = []
    for module, targets in GRAPH.items():
        here = _floor(module)
        if here is None:
            continue
        for target in targets:
            there = _floor(target)
            if there is not None and there > here:
                upward.append(f"{module} (floor {FLOORS[here]}) imports {target} (floor {FLOORS[there]})")
    assert not upward, "imports that run back up the floors:\n" + "\n".join(sorted(upward))


def _strongly_connected_components(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's algorithm (iterative)."""
    index, low, on_stack, stack, components = {}, {}, set(), [], []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    components.append(sorted(component))
    return components


def test_tarjan_finds_a_known_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert _strongly_connected_components(graph) == [["a", "b", "c"]]


def test_no_cycles_between_modules():
    cycles = _strongly_connected_components(GRAPH)
    assert not cycles, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in cycles)


def test_no_module_above_the_line_limit():
    lines = {m: len(p.read_text(encoding="utf-8").splitlines()) for m, p in MODULES.items()}
    long = [f"{MODULES[m].relative_to(SRC)}: {n} lines" for m, n in sorted(lines.items()) if n > MAX_LINES]
    assert not long, f"modules above {MAX_LINES} lines (split them by concept):\n" + "\n".join(long)


def test_demo_code_lives_in_the_demo_package():
    """Library packages hold only the library: no ``examples`` modules of demo hooks outside ``nmmm.demo``."""
    stray = sorted(m for m in MODULES if m.rsplit(".", 1)[-1] in ("examples", "demo") and not m.startswith("nmmm.demo"))
    assert not stray, f"demo modules inside library packages (move them to nmmm.demo): {stray}"
