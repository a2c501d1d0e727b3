"""The built-in models: stand descriptions in derive/stands/*.toml, and the coarse stand of 001."""
from pathlib import Path

from .description import load
from .norm import NormModel

STANDS_DIR = Path(__file__).resolve().parent / "stands"


def _rel(path):
    return path.relative_to(STANDS_DIR.parent.parent).as_posix()


#: Stand models by module name, each read from its description file.
MODELS = {p.stem: load(p, source_file=_rel(p)) for p in sorted(STANDS_DIR.glob("*.toml"))}
TWO_AXIS_MODEL = MODELS["two_axis"]
for _key, _model in MODELS.items():
    if _model.stand.name != _key:
        raise ValueError(f"derive/stands/{_key}.toml: stand.name must be {_key!r}, the file's name")

# The coarse stand of 001; pendulosity axes (i, j, k) = (2, 3, 1).
NORM_MODELS = {"norm": NormModel(axes=(2, 3, 1))}
