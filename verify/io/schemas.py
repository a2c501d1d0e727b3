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


@functools.cache
def fields(name):
    """{field: its meaning} of docs/schemas/NAME.schema.json's top level, in the schema's order: the one home of
    every field, which the API's result kinds (FIELDS) and docs/fields.md take."""
    schema = json.loads((FOLDER / f"{name}.schema.json").read_text())
    return {k: v.get("description", "") for k, v in schema["properties"].items()}


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
    """DataError for the first problem (by place in the file) of `data` against docs/schemas/NAME.schema.json.
    Arrays longer than the schema allows are refused first, by length alone (no item is looked at)."""
    long = _too_long(data, _validator(name).schema)
    if long:
        raise DataError(f"{path}: {_where(long[0])}: {long[1]} (schema {name}.schema.json)", param=name)
    errors = sorted(_validator(name).iter_errors(data), key=lambda e: [str(p) for p in e.absolute_path])
    if errors:
        e = errors[0]
        raise DataError(f"{path}: {_where(e.absolute_path)}: {_what(e)} (schema {name}.schema.json)", param=name)


def _where(place):
    """A place in a JSON document as a field path: primal[3].weight."""
    return "".join(f"[{p}]" if isinstance(p, int) else (f".{p}" if i else str(p))
                   for i, p in enumerate(place)) or "the top level"


def _too_long(node, schema, place=()):
    """(place, complaint) of the first array longer than its schema's maxItems, or None: checked from
    the top down, so a 10^6-item array is refused before any of its items is validated."""
    if isinstance(node, list):
        most = schema.get("maxItems")
        if most is not None and len(node) > most:
            return place, f"has {len(node):,} items, at most {most:,}"
        items = schema.get("items")
        if isinstance(items, dict):
            for i, v in enumerate(node):
                found = _too_long(v, items, (*place, i))
                if found:
                    return found
    elif isinstance(node, dict):
        for key, sub in schema.get("properties", {}).items():
            found = key in node and _too_long(node[key], sub, (*place, key))
            if found:
                return found
    for sub in schema.get("allOf", ()):
        found = _too_long(node, sub, place)
        if found:
            return found
    return None


def _count(schema):
    """How many items an array schema allows, in words: "3", "at least 1", "at most 12"."""
    lo, hi = schema.get("minItems"), schema.get("maxItems")
    return f"{lo}" if lo == hi else f"at least {lo}" if hi is None else f"at most {hi}" if lo is None else \
        f"{lo} to {hi}"


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
                           "minItems": f"must have {_count(e.schema)} items",
                           "maxItems": f"must have {_count(e.schema)} items",
                           "maxLength": f"is longer than {e.validator_value} characters"}.get(
        e.validator, e.message[:120].encode("unicode_escape").decode())
