"""The layering of the project, read from the source with :mod:`ast` (nothing is imported).

- ``drivers/`` imports nothing from ``harness/``: the drivers know CAN and units, not the
  profile, the controller or the supervisor (docs/ARCHITECTURE.md, "One direction").
- Inside ``drivers/`` the protocol (``drivers.protocol``) imports no transport and no role, the
  transports (``drivers.transports``) import the protocol but no role, and the roles (the reader,
  the writers, the link) keep the few loose modules of :data:`DRIVER_LOOSE_MODULES`.
- No two modules import each other, even inside a function or only for a type: the import
  graph has no cycle.
  An import of a package's module counts as an import of the package too, since Python runs
  the package's ``__init__`` first (``harness.recording.strict_json`` runs the recording
  package's, which starts the recorder's modules).
- Imports run one way, from the top down: the command line and the commands, then the
  runs (with the sweep and the live console), then the loop and the simulation, then the
  rig, control and safety, then the model, the motions, the run folders and CAN
  (``harness.canbus``), then the foundation: configuration, errors, the host's real time
  and the signals' names. The test checks the layers that have a rule of their own:
  nothing below imports a command or a run, nothing below the loop and the simulation
  imports them, CAN imports only the foundation (and the drivers), and the foundation
  imports nothing else.
- ``harness/`` keeps at most six loose modules (:data:`LOOSE_MODULES`); everything else
  lives in a package named for its role.

:func:`project_imports` is the reusable part: per module, the project modules it imports,
imports inside functions and classes included (an import hidden in a function is still a
dependency). Imports made through ``importlib`` are not seen.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PACKAGES = ("drivers", "harness")


def module_name(path: Path, root: Path) -> str:
    """Dotted module name of the source file ``path`` under ``root`` (``drivers/__init__.py`` -> ``drivers``)."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def project_modules(root: Path, packages: Iterable[str] = PACKAGES) -> dict[str, Path]:
    """Every module of the given top-level packages under ``root``: dotted name -> source file."""
    modules = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            modules[module_name(path, root)] = path
    return modules


def _is_type_checking_block(node: ast.AST) -> bool:
    """True for ``if TYPE_CHECKING:`` and ``if typing.TYPE_CHECKING:``."""
    if not isinstance(node, ast.If):
        return False
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _import_nodes(tree: ast.AST, type_checking: bool) -> Iterable[ast.Import | ast.ImportFrom]:
    """Every import statement at any depth (functions, classes, try/if blocks included)."""
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif not type_checking and _is_type_checking_block(node):
            stack.extend(node.orelse)  # type: ignore[attr-defined]
        else:
            stack.extend(ast.iter_child_nodes(node))


def _absolute(node: ast.ImportFrom, importer: str, is_package: bool) -> str:
    """The absolute module a ``from ... import`` names (resolving ``from . import x`` and ``from ..a import b``)."""
    if not node.level:
        return node.module or ""
    package = importer.split(".") if is_package else importer.split(".")[:-1]
    base = package[: len(package) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _known(name: str, modules: dict[str, Path]) -> str:
    """The deepest project module that ``name`` is or lies in (``harness.errors.BusError`` -> ``harness.errors``)."""
    parts = name.split(".")
    for end in range(len(parts), 0, -1):
        candidate = ".".join(parts[:end])
        if candidate in modules:
            return candidate
    return name


def imported_names(path: Path, importer: str, *, type_checking: bool = True) -> set[str]:
    """Absolute dotted names of everything ``path`` imports: modules, and ``module.name`` for from-imports."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_package = path.name == "__init__.py"
    names = set()
    for node in _import_nodes(tree, type_checking):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        else:
            module = _absolute(node, importer, is_package)
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names if alias.name != "*")
    return names


def project_imports(
    root: Path = REPO, packages: Iterable[str] = PACKAGES, *, type_checking: bool = True
) -> dict[str, set[str]]:
    """Per project module, the project modules it imports, at any nesting level.

    Parameters
    ----------
    root : Path
        The checkout (the directory holding the packages).
    packages : iterable of str
        Top-level packages that make up the project.
    type_checking : bool
        Count imports under ``if TYPE_CHECKING:`` too (they name a dependency, though not one
        made at run time; leave them out for a check of import cycles at run time).

    Returns
    -------
    dict of str to set of str
        Module name -> names of the project modules it imports (its own name excluded). A
        from-import counts the module it imports from, and the submodule when the imported
        name is one (``from drivers.transports import seqpacket`` -> ``drivers``, ``drivers.transports.seqpacket``).
    """
    packages = tuple(packages)
    modules = project_modules(root, packages)
    graph = {}
    for name, path in modules.items():
        found = {_known(imported, modules) for imported in imported_names(path, name, type_checking=type_checking)}
        graph[name] = {dep for dep in found if dep.split(".")[0] in packages and dep != name}
    return graph


# --- the rules ------------------------------------------------------------------------------


def test_drivers_import_nothing_from_harness() -> None:
    graph = project_imports()
    assert any(name.startswith("drivers.") for name in graph), "no driver modules found"
    offenders = {
        module: sorted(dep for dep in deps if dep.split(".")[0] == "harness")
        for module, deps in graph.items()
        if module.split(".")[0] == "drivers"
    }
    offenders = {module: deps for module, deps in offenders.items() if deps}
    assert not offenders, f"drivers must not import harness; found: {offenders}"


#: What each part of the drivers may import of ``drivers``: the protocol knows no bus, the transports
#: carry frames without knowing the roles that read and write them (docs/ARCHITECTURE.md).
DRIVER_LAYERS = {
    "drivers.errors": ("drivers.errors",),
    "drivers.protocol": ("drivers.protocol", "drivers.errors"),
    "drivers.transports": ("drivers.transports", "drivers.protocol", "drivers.errors"),
}
#: The only modules directly in ``drivers/``: the package, the errors every part raises, and the roles
#: on any bus (the readers, the writers, the decoded control sample, the link that puts them together).
DRIVER_LOOSE_MODULES = ("__init__.py", "errors.py", "link.py", "measurements.py", "reader.py", "rig_reader.py", "writer.py")


def imports_leaving(graph: dict[str, set[str]], layers: dict[str, tuple[str, ...]], scope: str,
                    ignored: tuple[str, ...] = ()) -> list[str]:
    """``"module -> dep"`` for each import by a module of a layer of ``scope`` (a top package) that its layer does not allow.

    ``layers`` maps a layer to the layers its modules may import; ``ignored`` names modules any may import.
    """
    return sorted(
        f"{module} -> {dep}"
        for module, deps in graph.items()
        for layer, allowed in layers.items()
        if _in(module, layer)
        for dep in deps
        if _in(dep, scope) and dep not in ignored and not any(_in(dep, a) for a in allowed)
    )


def test_the_protocol_knows_no_transport_and_the_transports_no_role() -> None:
    graph = project_imports()
    assert all(any(_in(module, layer) for module in graph) for layer in DRIVER_LAYERS), "a driver layer without modules"
    upward = imports_leaving(graph, DRIVER_LAYERS, "drivers", ignored=("drivers",))
    assert not upward, f"driver imports from the protocol to a transport or a role, or from a transport to a role: {upward}"


def test_drivers_keep_only_the_roles_loose() -> None:
    loose = sorted(path.name for path in (REPO / "drivers").glob("*.py"))
    assert "reader.py" in loose, "not the drivers package"
    others = sorted(set(loose) - set(DRIVER_LOOSE_MODULES))
    assert not others, (
        f"drivers/ keeps only {', '.join(DRIVER_LOOSE_MODULES)} loose; move {others} to drivers/protocol/ or drivers/transports/"
    )


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(module: str) -> None:
        index[module] = low[module] = len(index)
        stack.append(module)
        on_stack.add(module)
        for dep in graph.get(module, ()):
            if dep not in graph:
                continue
            if dep not in index:
                visit(dep)
                low[module] = min(low[module], low[dep])
            elif dep in on_stack:
                low[module] = min(low[module], index[dep])
        if low[module] == index[module]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == module:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for module in sorted(graph):
        if module not in index:
            visit(module)
    return cycles


def with_packages_run_first(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """``graph`` with, for every import of a package's module from outside that package, the package too.

    ``import harness.recording.strict_json`` runs ``harness/recording/__init__.py`` (and
    ``harness/__init__.py``) first: those are dependencies of the importer as much as the
    module it names. From inside the package they are not: its ``__init__`` is already running.
    """
    expanded = {}
    for module, deps in graph.items():
        found = set(deps)
        for dep in deps:
            parts = dep.split(".")
            for end in range(1, len(parts)):
                package = ".".join(parts[:end])
                if package in graph and not _in(module, package):
                    found.add(package)
        expanded[module] = found - {module}
    return expanded


def test_the_import_graph_has_no_cycle() -> None:
    cycles = import_cycles(with_packages_run_first(project_imports(type_checking=False)))
    assert not cycles, f"modules that import each other (directly or round a ring): {cycles}"


def test_no_ring_either_through_imports_made_for_a_type() -> None:
    # An import under ``if TYPE_CHECKING:`` runs no code, but a ring kept for a type still makes
    # each module unreadable without the other (harness/report/build.py and harness/report/summary.py were one).
    cycles = import_cycles(project_imports(type_checking=True))
    assert not cycles, f"modules that import each other, counting imports for types: {cycles}"


def package_of(module: str) -> str:
    """The package a module belongs to, one level below the top (``harness.control``); a loose module is its own."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 2 else module


def package_imports(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The module graph folded onto packages: ``a -> b`` when a module of ``a`` imports one of ``b``."""
    folded: dict[str, set[str]] = {package_of(module): set() for module in graph}
    for module, deps in graph.items():
        folded[package_of(module)] |= {package_of(dep) for dep in deps} - {package_of(module)}
    return folded


def test_no_package_ring_either_counting_imports_made_for_a_type() -> None:
    """Issue 35, item 4: ``harness.profile`` puts the sections together and the packages never import it back
    (the control's factory reads a :class:`~harness.control.sections.ControlSections`, the virtual rig its
    :class:`~harness.rig.parts.RigParts`), and ``harness.signals`` does not reach into ``harness.recording``."""
    cycles = import_cycles(package_imports(project_imports(type_checking=True)))
    assert not cycles, f"packages that import each other (directly or round a ring): {cycles}"


def test_the_package_ring_finder_folds_modules_onto_their_packages() -> None:
    graph = {"harness.a.x": {"harness.b.y"}, "harness.b.y": {"harness.profile"}, "harness.profile": {"harness.a.z"},
             "harness.a.z": set()}
    assert package_imports(graph)["harness.a"] == {"harness.b"}
    assert import_cycles(package_imports(graph)) == [["harness.a", "harness.b", "harness.profile"]]


def config_modules(graph: dict[str, set[str]]) -> list[str]:
    """The settings of each section: every module named ``config`` in a package of ``harness``."""
    return sorted(module for module in graph if module.startswith("harness.") and module.endswith(".config")
                  and module != "harness.config")


def settings_only(graph: dict[str, set[str]], module: str) -> list[str]:
    """What ``module`` reaches at run time beyond settings: the foundation, the drivers' protocol values, other
    section configs, packages' ``__init__`` and leaves (modules that import nothing of the project but those)."""
    allowed_roots = (*FOUNDATION, "drivers.protocol.protocol_values")

    def plain(dep: str) -> bool:
        return any(_in(dep, root) for root in allowed_roots) or dep in graph and dep.endswith(".config")

    def leaf(dep: str) -> bool:
        return all(plain(inner) or _is_package(inner) for inner in graph.get(dep, ()))

    reached, stack = set(), [module]
    while stack:
        for dep in graph.get(stack.pop(), ()):
            if dep not in reached:
                reached.add(dep)
                stack.append(dep)
    return sorted(dep for dep in reached if not (plain(dep) or _is_package(dep) or leaf(dep)))


def _is_package(module: str) -> bool:
    path = REPO.joinpath(*module.split("."))
    return (path / "__init__.py").is_file()


def test_the_section_configs_hold_settings_only() -> None:
    """Issue 35, item 4: a section's ``config`` module is settings (dataclasses and their checks), so the profile
    that gathers them does not start the controllers, the models or the rig: each reaches only the foundation,
    other configs and leaves of plain settings (the designs, the building's and the bearing's values)."""
    graph = with_packages_run_first(project_imports(type_checking=False))
    configs = config_modules(graph)
    assert {"harness.control.config", "harness.loop.config", "harness.rig.config", "harness.safety.config"} <= set(configs)
    beyond = {module: settings_only(graph, module) for module in configs}
    beyond = {module: deps for module, deps in beyond.items() if deps}
    assert not beyond, f"section configs that reach more than settings: {beyond}"


def test_the_settings_rule_sees_logic_behind_a_config() -> None:
    graph = {"harness.a.config": {"harness.a.logic"}, "harness.a.logic": {"harness.b.solver"}, "harness.b.solver": set(),
             "harness.b.config": {"harness.config.schema"}, "harness.config.schema": set()}
    assert settings_only(graph, "harness.a.config") == ["harness.a.logic"]
    assert settings_only(graph, "harness.b.config") == []


#: Layers with a rule of their own: a module may import these only from the layers named.
#: The live console (``harness.console``) is a view of the loop's status, drawn for a run: it
#: sits with the runs; so does the replay of a run (``harness.replay``), a run of the loop on its log.
_RUNS = ("harness.cli", "harness.commands", "harness.runs", "harness.sweep", "harness.console", "harness.replay")
UPPER_LAYERS = {
    "harness.commands": ("harness.cli", "harness.commands"),
    "harness.runs": _RUNS,
    "harness.loop": (*_RUNS, "harness.loop", "harness.simulation"),
    "harness.simulation": (*_RUNS, "harness.simulation"),
}

#: The one exception, and why: the profile is every section's configuration put together,
#: so it imports each package's ``config`` module (a leaf of plain dataclasses), the loop's too.
SECTION_CONFIGS = {("harness.profile", "harness.loop.config")}

#: The bottom layer: configuration (schema, units, YAML, input limits), errors, exit codes,
#: paths, the host's real time (scheduler, memory, SCHED_FIFO) and the signals (the per-sample
#: columns and the peaks computed from them). Everything may import it; it imports only itself.
FOUNDATION = ("harness.config", "harness.errors", "harness.exit_codes", "harness.paths", "harness.realtime",
              "harness.signals")
#: Lower layers with a rule of their own: a module of the layer may import, of ``harness``, only
#: itself and the layers named (the drivers are below them all).
LOWER_LAYERS = {
    **{package: FOUNDATION for package in FOUNDATION},
    "harness.canbus": (*FOUNDATION, "harness.canbus"),
}


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def test_imports_run_from_the_commands_down() -> None:
    graph = project_imports(type_checking=False)
    upward = sorted(
        f"{module} -> {dep}"
        for module, deps in graph.items()
        for dep in deps
        for layer, allowed in UPPER_LAYERS.items()
        if _in(dep, layer) and not any(_in(module, a) for a in allowed) and (module, dep) not in SECTION_CONFIGS
    )
    assert not upward, f"imports that run upward: {upward}"


def test_the_lower_layers_import_only_what_lies_below_them() -> None:
    graph = project_imports(type_checking=False)
    assert all(any(_in(module, layer) for module in graph) for layer in LOWER_LAYERS), "a layer without modules"
    upward = imports_leaving(graph, LOWER_LAYERS, "harness")
    assert not upward, f"imports that run upward from the foundation or CAN: {upward}"


#: The only modules directly in ``harness/``: the package, the command line's entry, the errors,
#: the exit statuses, the project's paths and the profile (every section put together). Any
#: other module goes into the package of its role (``config``, ``realtime``, ``signals``, ...).
LOOSE_MODULES = ("__init__.py", "cli.py", "errors.py", "exit_codes.py", "paths.py", "profile.py")


def test_harness_keeps_at_most_six_loose_modules() -> None:
    loose = sorted(path.name for path in (REPO / "harness").glob("*.py"))
    assert "cli.py" in loose, "not the harness package"
    assert len(LOOSE_MODULES) <= 6
    others = sorted(set(loose) - set(LOOSE_MODULES))
    assert not others, f"harness/ keeps only {', '.join(LOOSE_MODULES)} loose; move {others} into a package"


def test_the_cycle_finder_finds_a_ring() -> None:
    ring = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert import_cycles(ring) == [["a", "b", "c"]]
    assert import_cycles({"a": {"b"}, "b": set()}) == []


def test_an_import_of_a_packages_module_runs_the_package_first() -> None:
    # pkg/__init__ imports pkg.inner, which imports low; low imports pkg.leaf: a ring through pkg/__init__.
    graph = {"pkg": {"pkg.inner"}, "pkg.inner": {"low"}, "pkg.leaf": set(), "low": {"pkg.leaf"}}
    assert import_cycles(graph) == []
    expanded = with_packages_run_first(graph)
    assert expanded["low"] == {"pkg.leaf", "pkg"}
    assert expanded["pkg.inner"] == {"low"}, "inside the package its __init__ is already running"
    assert import_cycles(expanded) == [["low", "pkg", "pkg.inner"]]


# --- the helper itself ----------------------------------------------------------------------


def test_import_walker_sees_nested_relative_and_type_checking_imports(tmp_path: Path) -> None:
    (tmp_path / "low").mkdir()
    (tmp_path / "low" / "__init__.py").write_text("from . import leaf\n")
    (tmp_path / "low" / "leaf.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from high.types import Thing\n"
        "def late():\n    import high.deep as deep\n    return deep\n"
        "class Kind:\n    def method(self):\n        from ..high import config\n"
    )
    (tmp_path / "high").mkdir()
    (tmp_path / "high" / "__init__.py").write_text("")
    for name in ("types", "deep", "config"):
        (tmp_path / "high" / f"{name}.py").write_text("import os\nfrom low.leaf import late\n")
    graph = project_imports(tmp_path, ("low", "high"))
    assert graph["low"] == {"low.leaf"}
    assert graph["low.leaf"] == {"high", "high.types", "high.deep", "high.config"}
    assert graph["high.deep"] == {"low.leaf"}, "stdlib imports are not project modules"
    at_run_time = project_imports(tmp_path, ("low", "high"), type_checking=False)
    assert at_run_time["low.leaf"] == {"high", "high.deep", "high.config"}
