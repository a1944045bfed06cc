"""What a wheel install needs: every subpackage listed in pyproject.toml (the wheel run of .ci/run
installs one and runs the demo with it)."""

import re
from pathlib import Path

import pytest

REPOSITORY = Path(__file__).resolve().parents[1]


def test_every_subpackage_is_installed_with_the_package():
    """pyproject.toml lists the packages by hand (the configs and models are mapped into it): a new
    subpackage left out of the list is missing from a wheel install."""
    text = (REPOSITORY / "pyproject.toml").read_text()
    listed = set(re.findall(r'"(rlcontroller[a-z_.]*)"', text.split("packages = [", 1)[1].split("]", 1)[0]))
    folders = {
        "rlcontroller"
        + "".join(f".{part}" for part in init.parent.relative_to(REPOSITORY / "rlcontroller").parts)
        for init in (REPOSITORY / "rlcontroller").rglob("__init__.py")
    }
    assert folders <= listed, sorted(folders - listed)


@pytest.mark.slow
def test_every_imported_distribution_is_a_declared_dependency():
    """A module imported by the package but installed only by another package's dependencies (click came with
    typer until typer vendored it) works in the development environment and fails in a wheel install."""
    import ast
    import importlib.metadata
    import sys

    text = (REPOSITORY / "pyproject.toml").read_text()
    block = text.split("dependencies = [", 1)[1].split("]", 1)[0]
    optional = text.split("[project.optional-dependencies]", 1)[1].split("[project.scripts]", 1)[0]
    declared = {  # "dask[distributed]" declares dask and its extra's distribution
        name.lower().replace("_", "-")
        for requirement in re.findall(r'"([A-Za-z0-9_.\-]+(?:\[[a-z,\-]+\])?)', block + optional)
        for name in re.split(r"[\[\],]", requirement)
        if name
    }
    distributions = importlib.metadata.packages_distributions()
    imported: dict[str, str] = {}
    for source in (REPOSITORY / "rlcontroller").rglob("*.py"):
        tree = ast.parse(source.read_text(), filename=str(source))
        fallbacks = {  # `except ImportError:` branches: what an older version of a dependency needs
            id(inner)
            for handler in ast.walk(tree)
            if isinstance(handler, ast.ExceptHandler) and getattr(handler.type, "id", "") == "ImportError"
            for inner in ast.walk(handler)
        }
        for node in ast.walk(tree):
            if id(node) in fallbacks:
                continue
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top != "rlcontroller" and top not in sys.stdlib_module_names:
                    imported.setdefault(top, str(source.relative_to(REPOSITORY)))
    undeclared = {
        top: where
        for top, where in imported.items()
        if not {d.lower().replace("_", "-") for d in distributions.get(top, [top])} & declared
    }
    assert not undeclared, undeclared
