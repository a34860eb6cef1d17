"""How campar is found: a script in a folder that also holds the clone (``~/campar`` beside
``~/script.py``) imports the package, not the clone folder as an empty namespace package."""

import subprocess
import sys
from pathlib import Path

import pytest

REPOSITORY = Path(__file__).resolve().parents[1]

SCRIPT = """
import campar
print(campar.__file__)
print(callable(campar.simulate_point), callable(campar.run))
"""


@pytest.mark.process
def test_a_script_beside_the_clone_folder_imports_the_package(tmp_path):
    (tmp_path / "campar").symlink_to(REPOSITORY, target_is_directory=True)  # ~/campar: a clone
    script = tmp_path / "script.py"
    script.write_text(SCRIPT)
    out = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert out.returncode == 0, out.stderr
    where, found = out.stdout.splitlines()
    assert Path(where).resolve() == REPOSITORY / "campar" / "__init__.py"
    assert found == "True True"
