import re
import tomllib
from pathlib import Path

PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"


def test_license_is_an_spdx_string_with_a_setuptools_that_reads_it():
    data = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))
    # A TOML table here makes setuptools ≥ 77 print a deprecation warning on every install.
    assert data["project"]["license"] == "MIT"
    assert not any(c.startswith("License ::") for c in data["project"].get("classifiers", []))
    (req,) = [r for r in data["build-system"]["requires"] if r.startswith("setuptools")]
    minimum = re.fullmatch(r"setuptools>=(\d+)(\.\d+)*", req)
    assert minimum and int(minimum.group(1)) >= 77  # the first setuptools that reads SPDX strings


def test_vision_extra_is_headless_opencv_and_the_ci_installs_it():
    data = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))
    (req,) = data["project"]["optional-dependencies"]["vision"]
    assert req.startswith("opencv-python-headless")  # no GUI libraries on servers and CI
    ci = (PYPROJECT.parent / ".ci" / "run").read_text(encoding="utf-8")
    readme = (PYPROJECT.parent / "README.md").read_text(encoding="utf-8")
    command = 'pip install -e ".[test,ray,vision]"'
    assert command in ci and command in readme
