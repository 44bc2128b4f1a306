"""World files written for the tests of this folder (imported by name, as ``tests/vehicles/car_fixtures.py``)."""

from pathlib import Path


def write(tmp_path: Path, text: str, name: str = "w.yaml") -> Path:
    """Write ``text`` as the world file ``tmp_path / name`` and return its path."""
    path = tmp_path / name
    path.write_text(text)
    return path
