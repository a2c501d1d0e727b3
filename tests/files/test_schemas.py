"""The JSON schemas of docs/schemas/ are the one home of every field: every key a command writes is a property,
with its meaning, and a schema admits nothing else (additionalProperties false at every object of fixed keys)."""
import json

import numpy as np
import pytest

from garant.verify.cli import main
from garant.verify.io.schemas import FOLDER
from conftest import REAL, ROOT, needs_real

SCHEMAS = sorted(p.name.removesuffix(".schema.json") for p in FOLDER.glob("*.schema.json"))


def _errors(name, document):
    """Every complaint of the schema NAME about the document (its place and message)."""
    import jsonschema
    schema = json.loads((FOLDER / f"{name}.schema.json").read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return [f"{list(e.absolute_path)}: {e.message[:300]}"
            for e in jsonschema.Draft202012Validator(schema).iter_errors(document)]


def _objects(node, place=""):
    """(place, schema) of every object schema with fixed properties, outside if/then/else."""
    if isinstance(node, dict):
        if "properties" in node and not any(w in place for w in ("/if", "/then", "/else")):
            yield place, node
        for k, v in node.items():
            yield from _objects(v, f"{place}/{k}")
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _objects(v, f"{place}[{i}]")


@pytest.mark.parametrize("name", SCHEMAS)
def test_every_schema_admits_no_key_it_does_not_describe(name):
    schema = json.loads((FOLDER / f"{name}.schema.json").read_text())
    loose = [place or "the top level" for place, node in _objects(schema)
             if node.get("additionalProperties", True) is True]
    assert not loose, loose
    undescribed = [k for k, v in schema["properties"].items() if not v.get("description")]
    assert not undescribed, undescribed


def _run(args, code=0):
    got = main(args)
    assert code is None or got == code, args


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """What the commands write with --json, in the variants a user meets: (schema, kind) -> document."""
    t = tmp_path_factory.mktemp("json")
    d, s = t / "d.csv", t / "s.csv"
    _run(["simulate", "--model", "two-axis", "--plan", "quarter", "--sigma", "1e-5", "-o", str(d)])
    out = {}

    def run(schema, kind, args, code=0):
        path = t / f"{kind}.json"
        _run([*args, "--json", str(path)], code)
        out[schema, kind] = json.loads(path.read_text())

    run("estimate", "consistent", ["estimate", "--model", "two-axis", str(d), "--sigma", "1e-5"])
    run("estimate", "mounting", ["estimate", "--model", "two-axis", str(d), "--sigma", "1e-5", "--mount", "+x+y+z"])
    run("next", "measure", ["next", "--model", "two-axis", str(d), "--sigma", "1e-5"])
    text = d.read_text().splitlines()
    s.write_text("\n".join(text[:3]) + "\n")
    run("next", "start", ["next", "--model", "two-axis", str(s), "--sigma", "1e-5"])
    cells = text[1].split(",")
    cells[4] = str(float(cells[4]) + 0.1)                         # f3 1000 sigma off: inconsistent
    bad = t / "bad.csv"
    bad.write_text("\n".join([text[0], ",".join(cells), *text[2:]]) + "\n")
    run("estimate", "inconsistent", ["estimate", "--model", "two-axis", str(bad), "--sigma", "1e-5"], 3)
    rep = t / "rep.csv"
    rep.write_text("\n".join([text[0], text[1], ",".join(cells), *text[2:]]) + "\n")
    run("estimate", "repeated", ["estimate", "--model", "two-axis", str(rep), "--sigma", "1e-5"], 3)
    chamber = t / "chamber.csv"
    _run(["simulate", "--model", "two-axis", "--plan", "quarter16", "--temperatures=-20,0,20,40,60", "--sigma", "1e-5",
          "-o", str(chamber)])
    run("estimate", "thermal", ["estimate", "--model", "two-axis", str(chamber), "--sigma", "1e-5", "--g", "9.81",
                                "--thermal-degree", "2"])
    run("plan", "stand", ["plan", "--model", "two-axis"])
    run("identify", "stand", ["identify", "--model", "two-axis"])
    run("identify", "plan", ["identify", "--model", "two-axis", "--plan", str(d)])
    run("identify", "003", ["identify", "--model", "003-example1"])
    out["truth", "simulate"] = json.loads(d.with_suffix(".truth.json").read_text())
    out["truth", "chamber"] = json.loads(chamber.with_suffix(".truth.json").read_text())
    logs = [str(REAL / f"repeat_session{k}_acc.txt") for k in (2, 3, 4)]
    run("repeatability", "three runs", ["repeatability", *logs, "--g", "9.81744"])
    run("plan-temperatures", "chamber", ["plan", "--model", "two-axis", "--temperatures=-20,0,20,40,60"])
    run("plan-norm", "001", ["plan", "--model", "norm"])
    return out


@pytest.fixture(scope="module")
def slow_outputs(tmp_path_factory):
    """The documents of the commands that take seconds (diagnose's search, verify's 235 checks): the slow lane's."""
    t = tmp_path_factory.mktemp("slow")
    d, bad = t / "d.csv", t / "bad.csv"
    _run(["simulate", "--model", "two-axis", "--plan", "quarter", "--sigma", "1e-5", "-o", str(d)])
    text = d.read_text().splitlines()
    cells = text[1].split(",")
    cells[4] = str(float(cells[4]) + 0.1)                         # f3 1000 sigma off: inconsistent
    bad.write_text("\n".join([text[0], ",".join(cells), *text[2:]]) + "\n")
    out = {}
    for schema, kind, args, code in (
            ("diagnose", "consistent", ["diagnose", "--model", "two-axis", str(d), "--sigma", "1e-5"], 0),
            ("diagnose", "inconsistent", ["diagnose", "--model", "two-axis", str(bad), "--sigma", "1e-5"], None),
            ("verify", "all", ["verify"], 0)):
        path = t / f"{schema}-{kind}.json"
        _run([*args, "--json", str(path)], code)
        out[schema, kind] = json.loads(path.read_text())
    return out


EXPECTED = {("estimate", k) for k in ("consistent", "mounting", "inconsistent", "repeated", "thermal")} | {
    ("next", "measure"), ("next", "start"), ("plan", "stand"), ("plan-temperatures", "chamber"), ("plan-norm", "001"),
    ("identify", "stand"), ("identify", "plan"), ("identify", "003"), ("truth", "simulate"), ("truth", "chamber"),
    ("repeatability", "three runs")}
SLOW = {("diagnose", "consistent"), ("diagnose", "inconsistent"), ("verify", "all")}
CASES = [*sorted(EXPECTED), *(pytest.param(*x, marks=pytest.mark.slow) for x in sorted(SLOW))]


def _document(request, schema, kind):
    return request.getfixturevalue("slow_outputs" if (schema, kind) in SLOW else "outputs")[schema, kind]


@pytest.mark.parametrize("schema, kind", CASES)
def test_every_key_a_command_writes_is_a_property_of_its_schema(request, schema, kind):
    # A key outside the schema, or a value of another type than the schema states, turns it red.
    assert _errors(schema, _document(request, schema, kind)) == []


@pytest.mark.parametrize("schema, kind", CASES)
def test_each_schema_refuses_a_key_nobody_described(request, schema, kind):
    assert _errors(schema, {**_document(request, schema, kind), "unknown_key": 1})


def test_the_schemas_can_fail(outputs):
    broken = dict(outputs["estimate", "consistent"])
    broken.pop("premises")
    assert _errors("estimate", broken)
    broken = dict(outputs["estimate", "consistent"])
    broken.pop("q")
    assert _errors("estimate", broken)
    assert _errors("plan", dict(outputs["plan", "stand"], min_positions_proven="yes"))


def test_the_calibration_inside_a_result_is_a_calibration_file(outputs):
    assert _errors("calibration", outputs["estimate", "consistent"]["calibration"]) == []


@needs_real
def test_a_batchs_unit_files_are_calibration_files(tmp_path):
    logs = [str(REAL / "repeat_session2_acc.txt"), str(REAL / "imu_tk_xsens_acc.txt")]
    assert main(["calibrate-norm", *logs, "--out", str(tmp_path / "o")]) == 0
    units = sorted((tmp_path / "o").glob("*.json"))
    assert len(units) == 2
    for unit in units:
        assert _errors("calibration", json.loads(unit.read_text())) == [], unit.name


def test_premises_are_one_type_in_every_result(outputs):
    # A norm calibration's premises were a string, an estimate's an object: both are objects with a statement.
    log = ROOT / "tests" / "data" / "imucal" / "example_ferraris_session.csv"
    from garant.verify.workflows import jobs
    norm = jobs.calibrate_norm(str(log), format="imucal", rate=102.4,
                               bound={"alpha": 1e-2, "beta": 1e-2, "gamma": 1e-2}).to_dict()
    for doc in (norm, outputs["estimate", "consistent"], outputs["estimate", "thermal"]):
        assert isinstance(doc["premises"], dict) and doc["premises"]["statement"]
    assert np.isfinite(norm["premises"]["g"])
