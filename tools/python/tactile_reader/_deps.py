"""The Python modules tactile_reader needs from Debian, imported with a message that names the
missing package and the interpreter in use (a Python without Debian's dist-packages, such as a
pyenv or venv interpreter, is the usual cause)."""

import importlib
import sys

# module -> the Debian package that provides it for /usr/bin/python3
DEBIAN_PACKAGES = {
    "google.protobuf": "python3-protobuf",
    "zstandard": "python3-zstandard",
    "zmq": "python3-zmq",
}


class MissingDependency(ImportError):
    """A module of DEBIAN_PACKAGES that this interpreter cannot import."""


def require(module: str):
    """The module, or MissingDependency naming its Debian package and sys.executable."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        package = DEBIAN_PACKAGES[module]
        version = ".".join(str(v) for v in sys.version_info[:3])
        raise MissingDependency(
            f"tactile_reader needs the Python module '{module}' from the Debian package {package}, "
            f"and the interpreter in use, {sys.executable or 'python3'} (Python {version}), cannot "
            f"import it ({e}). Install it with 'apt-get install {package}' (scripts/install-deps "
            "--test does) and run Debian's /usr/bin/python3, or make it importable by this "
            "interpreter."
        ) from e
