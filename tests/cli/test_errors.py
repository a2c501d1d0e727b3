"""Typed errors: every DataError names the parameter it is about, and the command line turns only DataError (and
the solver's LPFailed) into a one-line bad-input message."""
import ast

import pytest

from garant.verify.errors import DataError
from conftest import ROOT


def _sites():
    """(file, line, call) of every DataError(...) in the package's code."""
    for folder in ("verify", "derive"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", None)) == \
                        "DataError":
                    yield f"{path.relative_to(ROOT)}:{node.lineno}", node


def _names_its_parameter(call):
    """param= given, or an option marked in the text with opt(NAME) (the first names it)."""
    return (any(k.arg == "param" for k in call.keywords) or len(call.args) > 1
            or any(isinstance(n, ast.Call) and getattr(n.func, "id", None) == "opt" for n in ast.walk(call)))


@pytest.mark.slow
def test_every_data_error_names_its_parameter():
    # Red when a DataError is raised with no param (46 of 242 sites named one before).
    sites = list(_sites())
    assert len(sites) > 250
    assert [where for where, call in sites if not _names_its_parameter(call)] == []


def test_the_check_sees_a_site_without_a_parameter(tmp_path):
    call = ast.parse('raise DataError(f"{path}: bad")').body[0].exc
    assert not _names_its_parameter(call)
    assert _names_its_parameter(ast.parse('raise DataError("x", param="log")').body[0].exc)
    assert _names_its_parameter(ast.parse('raise DataError(f"give {opt(\'imu\')} K")').body[0].exc)


@pytest.mark.parametrize("call, param", [
    (lambda g: g.estimate("two-axis", "/nonexistent.csv", 1e-5), "data"),
    (lambda g: g.estimate("two-axis", [[0, 0, 0, 0, 9.81]], -1.0), "sigma"),
    (lambda g: g.calibrate_norm("/nonexistent.txt"), "log"),
    (lambda g: g.apply("/nonexistent.json", "/nonexistent.txt"), "calibration"),
    (lambda g: g.plan("no-such-stand"), "model"),
])
def test_an_api_error_names_the_argument_the_caller_gave(call, param):
    import garant
    with pytest.raises(DataError) as e:
        call(garant)
    assert e.value.param == param


def test_a_value_error_that_is_not_bad_input_is_not_called_bad_input(monkeypatch, capsys):
    # The command line once took any ValueError for bad input (exit 2, "error: ..."): a bug inside would read as
    # the user's mistake. Now it says it is garant's own failure, with exit status 1 and no traceback.
    from garant.verify.cli import main
    from garant.verify.workflows import plan

    def broken(*a, **k):
        raise ValueError("operands could not be broadcast together")
    monkeypatch.setattr(plan, "plan", broken)
    assert main(["plan", "--model", "two-axis"]) == 1
    err = capsys.readouterr().err
    assert "internal error" in err and "Traceback" not in err
