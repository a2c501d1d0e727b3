"""The published JSON Schemas of the files garant reads and writes (docs/schemas/, shipped with the
package), checked with `jsonschema`: one line naming the file, the field and what is wrong."""
import functools
import json
from pathlib import Path

from ..errors import DataError

#: The folder of the schemas: docs/schemas/ of the package root (the repository root, installed as garant).
FOLDER = Path(__file__).resolve().parents[2] / "docs" / "schemas"


@functools.cache
def _validator(name):
    import jsonschema
    schema = json.loads((FOLDER / f"{name}.schema.json").read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(_inlined(schema, schema.get("$defs", {})))


def _inlined(node, defs):
    """The schema with each local reference "#/$defs/X" replaced by X itself (the published schemas are
    not recursive): the same constraints, checked without a reference lookup per value."""
    if isinstance(node, dict):
        ref = node.get("$ref", "")
        if ref.startswith("#/$defs/") and "allOf" not in node:
            target = _inlined(defs[ref.removeprefix("#/$defs/")], defs)
            rest = {k: _inlined(v, defs) for k, v in node.items() if k != "$ref"}
            return {**rest, "allOf": [target]} if rest else target      # a $ref beside other keywords: both hold
        return {k: _inlined(v, defs) for k, v in node.items()}
    if isinstance(node, list):
        return [_inlined(v, defs) for v in node]
    return node


def validate(data, name, path):
    """DataError for the first problem (by place in the file) of `data` against docs/schemas/NAME.schema.json."""
    errors = sorted(_validator(name).iter_errors(data), key=lambda e: [str(p) for p in e.absolute_path])
    if errors:
        e = errors[0]
        where = "".join(f"[{p}]" if isinstance(p, int) else (f".{p}" if i else str(p))
                        for i, p in enumerate(e.absolute_path)) or "the top level"
        raise DataError(f"{path}: {where}: {_what(e)} (schema {name}.schema.json)")


def _what(e):
    """The schema's complaint in a few words, the offending value shown escaped and short."""
    value = repr(e.instance)
    value = value if len(value) <= 60 else value[:57] + "..."
    if e.validator == "additionalProperties":
        return "unknown field(s): " + e.message.split("(")[-1].rstrip(")").replace(" were unexpected", "")\
            .replace(" was unexpected", "")
    if e.validator == "required":
        return e.message.replace("is a required property", "is missing")
    if e.validator == "pattern":
        return f"{value} holds control characters"
    limit = e.validator_value
    limit = f"{limit:g}" if isinstance(limit, float) else limit
    return f"{value}: " + {"enum": f"must be one of {e.validator_value}",
                           "const": f"must be {e.validator_value!r}",
                           "type": f"must be of type {e.validator_value}",
                           "minimum": f"must be >= {limit}",
                           "maximum": f"must be <= {limit}",
                           "minItems": f"must have {e.validator_value} items",
                           "maxItems": f"must have {e.validator_value} items",
                           "maxLength": f"is longer than {e.validator_value} characters"}.get(
        e.validator, e.message[:120].encode("unicode_escape").decode())
