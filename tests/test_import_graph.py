"""The steppers are pure integrators: no module of femrub/steppers imports a layer above."""

import ast
from pathlib import Path

import pytest

import femrub

STEPPERS = Path(femrub.__file__).parent / "steppers"
ABOVE = ("femrub.output", "femrub.scene", "femrub.app", "femrub.analysis")


def _imported(path: Path) -> set[str]:
    """Absolute names of every module imported anywhere in ``path`` (functions included)."""
    package = "femrub." + ".".join(path.relative_to(STEPPERS.parent).with_suffix("").parts)
    if path.name == "__init__.py":
        package += ".__init__"
    parts = package.split(".")[:-1]  # the module's package
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = parts[: len(parts) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names)
    return names


def _above(names: set[str]) -> list[str]:
    return sorted(n for n in names if any(n == a or n.startswith(a + ".") for a in ABOVE))


MODULES = sorted(STEPPERS.rglob("*.py"))


def test_every_steppers_module_is_parsed():
    names = {p.relative_to(STEPPERS).as_posix() for p in MODULES}
    assert {"base.py", "record.py", "theta.py", "exponential/stepper.py"} <= names


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.relative_to(STEPPERS).as_posix())
def test_steppers_import_no_layer_above(path):
    assert _above(_imported(path)) == []


def test_the_check_sees_relative_and_nested_imports(tmp_path, monkeypatch):
    """The parser resolves relative imports and finds imports inside functions."""
    fake = STEPPERS / "exponential" / "friction.py"
    source = "def f():\n    from ...output.recorder import StepRefused\n"
    monkeypatch.setattr(Path, "read_text", lambda self: source)
    assert _above(_imported(fake)) == [
        "femrub.output.recorder",
        "femrub.output.recorder.StepRefused",
    ]
    source2 = "import femrub.scene.validate as v\nfrom ..app import x\n"
    monkeypatch.setattr(Path, "read_text", lambda self: source2)
    assert _above(_imported(STEPPERS / "base.py")) == [
        "femrub.app",
        "femrub.app.x",
        "femrub.scene.validate",
    ]
