"""The export registry (verify/cli/exports.py): a new calibration file is one entry, and every command that
offers it adds its option, checks its path, refuses it where it cannot be written, and writes it."""
import json

import pytest

from garant.verify import cli
from garant.verify.cli import exports, main

from conftest import REAL, needs_real


def _demo(path, res, args):
    """A writer of the kind a new format needs: the calibration's M as JSON."""
    from garant.verify.io import report
    report.write_text(path, json.dumps(res["calibration"]["M"]))
    return f"wrote {path}"


@pytest.fixture
def demo(monkeypatch):
    """One more entry in the registry, nothing else changed."""
    entry = exports.Export("--export-demo", "FILE.json", "the demo file", "a demonstration format",
                           ("calibrate-norm",), "calibration", temperature=False, effects=False, write=_demo)
    monkeypatch.setattr(exports, "EXPORTS", exports.EXPORTS + (entry,))
    return entry


@needs_real
def test_one_registry_entry_gives_a_command_a_new_export(demo, tmp_path, capsys):
    log = str(REAL / "repeat_session2_acc.txt")
    out = tmp_path / "demo.json"
    # the option, with its help, and written from the result
    sub = cli.parser("calibrate-norm")._subparsers._group_actions[0].choices["calibrate-norm"]
    assert "a demonstration format" in sub.format_help().replace("\n", " ")
    assert main(["calibrate-norm", log, "--g", "9.81744", "--export-demo", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    assert len(json.loads(out.read_text())) == 3
    # its path checked before any work, as every output: never over an input
    assert main(["calibrate-norm", log, "--export-demo", log]) == 2
    assert "input" in capsys.readouterr().err
    # refused where it cannot be written: with --thermal-degree, in a batch; the estimate command does not offer it
    assert main(["calibrate-norm", log, "--thermal-degree", "1", "--export-demo", str(tmp_path / "t.json")]) == 2
    assert "--export-demo: that file holds no polynomial in T" in capsys.readouterr().err
    assert main(["calibrate-norm", log, log, "--out", str(tmp_path / "o"), "--export-demo", str(tmp_path / "b")]) == 2
    assert "--export-demo concerns one log" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["estimate", "--model", "two-axis", log, "--sigma", "1e-5", "--export-demo", str(tmp_path / "e.json")])
    assert "unrecognized arguments: --export-demo" in capsys.readouterr().err


def test_the_registry_names_every_calibration_file_of_the_commands():
    # Red when a command grows an --export-* option by hand, outside the registry.
    for command in ("estimate", "calibrate-norm"):
        options = {o for a in cli.parser(command)._subparsers._group_actions[0].choices[command]._actions
                   for o in a.option_strings if o.startswith("--export-") or o == "--save"}
        assert options == {e.option for e in exports.of(command)}, command


@pytest.mark.parametrize("option, value", [("--px4-device-id", "7"), ("--ardupilot-imu", "2"),
                                           ("--kalibr-topic", "/imu1"), ("--imucal-gyro", "g.json")])
def test_an_exports_own_option_without_the_export_is_refused_not_ignored(tmp_path, capsys, option, value):
    log = tmp_path / "log.txt"
    log.write_text("0 0 0 9.81\n")
    assert main(["calibrate-norm", str(log), option, value]) == 2
    err = capsys.readouterr().err
    assert option in err and ("goes with" in err or "--export-imucal" in err)
