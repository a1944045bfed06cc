"""What a wheel install needs: every subpackage listed in pyproject.toml (the wheel run of .ci/run
installs one and runs the demo with it)."""

import re
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[1]


def test_every_subpackage_is_installed_with_the_package():
    """pyproject.toml lists the packages by hand (the configs and models are mapped into it): a new
    subpackage left out of the list is missing from a wheel install."""
    text = (REPOSITORY / "pyproject.toml").read_text()
    listed = set(re.findall(r'"(rlcontroller[a-z_.]*)"', text.split("packages = [", 1)[1].split("]", 1)[0]))
    folders = {
        "rlcontroller" + "".join(f".{part}" for part in init.parent.relative_to(REPOSITORY / "rlcontroller").parts)
        for init in (REPOSITORY / "rlcontroller").rglob("__init__.py")
    }
    assert folders <= listed, sorted(folders - listed)
