"""Names imported across modules are public: an audit of every import in fuzzcore and monitor.

A private module (``pkg._kernels``) is imported only from inside its package ``pkg``; a
kernel module may also import another package's kernels (a Numba kernel can only call
kernels). A private name (``_x``) is never imported from another module.
"""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(source: str, package: str):
    """(imported module, imported names) of every import statement, absolute."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, ()
        elif isinstance(node, ast.ImportFrom) and node.module != "__future__":
            base = package.split(".")
            base = base[:len(base) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            yield module, tuple(alias.name for alias in node.names)


def _violations(importer: str, source: str, is_package: bool = False) -> list[str]:
    package = importer if is_package else importer.rpartition(".")[0]
    is_kernel_module = importer.rpartition(".")[2].endswith("kernels")

    def private(target: str) -> bool:
        parts = target.split(".")
        for i, part in enumerate(parts):
            if part.startswith("_") and not part.startswith("__"):
                owner = ".".join(parts[:i])
                inside = importer == owner or importer.startswith(owner + ".")
                return not ((inside and part.endswith("kernels"))
                            or (is_kernel_module and part.endswith("kernels")))
        return False

    found = []
    for module, names in _imports(source, package):
        targets = [module] if private(module) else [f"{module}.{n}" for n in names]
        found += [f"{importer} imports {t}" for t in targets if private(t)]
    return found


def test_the_audit_sees_violations():
    assert _violations("monitor.alignment", "from monitor.geometry import _box_kernels as _k") == [
        "monitor.alignment imports monitor.geometry._box_kernels"]
    assert _violations("monitor.report.figures", "from fuzzcore._kernels import mf_array") == [
        "monitor.report.figures imports fuzzcore._kernels"]
    assert _violations("monitor.cli.x", "from ..depth.retrieval import _block_means") == [
        "monitor.cli.x imports monitor.depth.retrieval._block_means"]
    assert _violations("fuzzcore.tune.objective", "import fuzzcore.membership._sorted") != []
    # allowed: a package's own private modules, kernels calling kernels, __future__
    assert _violations("fuzzcore.tune.objective", "from .. import _kernels as K\n"
                       "from . import _objective_kernels as KO") == []
    assert _violations("monitor._alignment_kernels", "from monitor.geometry._box_kernels import iou_one") == []
    assert _violations("fuzzcore", "from . import _kernels", is_package=True) == []
    assert _violations("monitor.x", "from __future__ import annotations") == []


def test_no_module_imports_a_private_name_of_another():
    found = [v for package in ("fuzzcore", "monitor") for path in sorted((ROOT / package).rglob("*.py"))
             for v in _violations(_module_name(path), path.read_text(), path.name == "__init__.py")]
    assert found == []
