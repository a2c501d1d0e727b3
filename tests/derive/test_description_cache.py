"""The cache of derived descriptions runs no one else's code: one entry per key, verified before it
is executed, in a folder only its owner can write."""
import hashlib
import os

import pytest

from garant.verify import models
from garant.verify.cli import main
from garant.verify.errors import DataError
from conftest import ROOT

STAND = ROOT / "derive" / "stands" / "single_axis.toml"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    folder.mkdir(mode=0o700)
    monkeypatch.setenv("GARANT_CACHE", str(folder))
    return folder


def _key():
    return hashlib.sha256(STAND.read_bytes() + models.generator_version().encode()).hexdigest()


def _planted(marker):
    return f"import pathlib\npathlib.Path({str(marker)!r}).write_text('ran')\n"


@pytest.mark.slow
@pytest.mark.parametrize("how", ["wrong hash", "no header", "old name that sorts first", "empty"])
def test_a_planted_entry_is_never_run_and_is_replaced(cache, tmp_path, how):
    # A file planted under the key (or, before, any `<key>-*.py`, the first in sort order) was executed by plan,
    # estimate and derive. Now the entry's first line must hold the SHA-256 of the rest: anything else is derived
    # again and replaced, never imported.
    marker = tmp_path / "marker"
    body = _planted(marker)
    text = {"wrong hash": f"# garant-cache single_axis {'0' * 64}\n{body}", "no header": body,
            "old name that sorts first": body, "empty": ""}[how]
    name = f"{_key()}-0.py" if how == "old name that sorts first" else f"{_key()}.py"
    (cache / name).write_text(text)
    mod = models.load(str(STAND))
    assert not marker.exists() and mod.ANGLES == ("phi",)
    head = (cache / f"{_key()}.py").read_text().splitlines()[0].split()
    assert head[:3] == ["#", "garant-cache", "single_axis"]
    assert models.load(str(STAND)).Q_NAMES == mod.Q_NAMES          # the genuine entry is used next time


@pytest.mark.parametrize("kind", ["fifo", "link to /dev/zero"])
def test_an_entry_that_is_not_a_regular_file_is_not_read(cache, kind):
    # A FIFO under the key blocked forever; a link to /dev/zero was read without a size cap.
    entry = cache / f"{_key()}.py"
    if kind == "fifo":
        os.mkfifo(entry)
    else:
        entry.symlink_to("/dev/zero")
    assert models.load(str(STAND)).ANGLES == ("phi",)


def test_a_cache_folder_others_can_write_is_refused_in_one_line(cache, capsys):
    cache.chmod(0o777)
    with pytest.raises(DataError, match="GARANT_CACHE"):
        models.load(str(STAND))
    assert main(["plan", "--model", str(STAND)]) == 2
    err = capsys.readouterr().err
    assert "writable by others" in err and len(err.strip().splitlines()) == 1
