"""Shared helpers of the peer benchmarks in bench/: the private virtual environment and the
release build of lightlab."""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(ROOT, "bench", ".venv")


def ensure_venv(packages):
    """A virtual environment in bench/.venv with `packages` installed (from PyPI); its python."""
    py = os.path.join(VENV, "bin", "python")
    if not os.path.exists(py):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    subprocess.check_call([py, "-m", "pip", "install", "-q", *packages])
    return py


def lightlab_exe():
    """Build lightlab in release mode and return the binary's path."""
    subprocess.check_call(["cargo", "build", "--release", "-q", "-p", "lightlab"], cwd=ROOT)
    return os.path.join(ROOT, "target", "release", "lightlab")
