"""Validate session JSON against ``schema.json`` and turn the best error into a SessionError.

The error names the session file, a JSON path such as ``camera.keyframes[2].eye`` and, for an
unknown key, the closest valid key (difflib).

>>> validate_fragment({"type": "box", "sise": 2}, "procedural", "s.json", "objects[0].procedural")
Traceback (most recent call last):
...
rrcache.errors.SessionError: s.json: objects[0].procedural.sise: unknown key 'sise' (hint: did you mean 'size'? valid keys: size, type)
"""
from __future__ import annotations

import difflib
import functools
import json
import re
from importlib import resources
from typing import Any, Iterable

import jsonschema
from jsonschema.exceptions import ValidationError, relevance

from rrcache.errors import SessionError

_TYPE_NAMES = {"number": "a number", "integer": "an integer", "string": "a string", "boolean": "true or false",
               "array": "an array", "object": "an object", "null": "null"}


@functools.lru_cache(maxsize=1)
def schema() -> dict:
    """The published session schema (draft 2020-12) as a dict."""
    return json.loads(resources.files("rrcache.session").joinpath("schema.json").read_text("utf-8"))


@functools.lru_cache(maxsize=None)
def _validator(definition: str | None) -> jsonschema.Draft202012Validator:
    s = schema()
    if definition is not None:
        s = {"$defs": s["$defs"], "$ref": f"#/$defs/{definition}"}
    return jsonschema.Draft202012Validator(s)


def json_path(parts: Iterable[Any], prefix: str = "") -> str:
    """``["camera", "keyframes", 2, "eye"]`` → ``camera.keyframes[2].eye``.

    >>> json_path(["objects", 1, "mesh"])
    'objects[1].mesh'
    """
    out = prefix
    for p in parts:
        if isinstance(p, int):
            out += f"[{p}]"
        elif re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", str(p)):
            out += f".{p}" if out else str(p)
        else:
            out += f"[{json.dumps(str(p))}]"
    return out


def _show(value: Any) -> str:
    text = json.dumps(value) if not isinstance(value, str) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _got(value: Any) -> str:
    """``string 'wide'``, ``integer 3``; just ``null`` for null."""
    return "null" if value is None else f"{_kind(value)} {_show(value)}"


def _kind(value: Any) -> str:
    for name, typ in (("boolean", bool), ("integer", int), ("number", float), ("string", str),
                      ("array", list), ("object", dict)):
        if isinstance(value, typ):
            return name
    return "null"


def _valid_keys(schema_node: dict) -> list[str]:
    return sorted(k for k in schema_node.get("properties", {}))


def _only_required(subschemas: list) -> list[str] | None:
    names = []
    for sub in subschemas:
        if not isinstance(sub, dict) or set(sub) != {"required"}:
            return None
        names += sub["required"]
    return names


def _pick(errors: list[ValidationError]) -> ValidationError | None:
    return min(errors, key=lambda e: (-len(e.absolute_path),) + tuple(relevance(e))) if errors else None


def _type_fails(errors: list[ValidationError], depth: int) -> bool:
    """Whether a branch of an anyOf/oneOf failed on the instance's type itself."""
    for e in errors:
        if len(e.absolute_path) != depth:
            continue
        if e.validator == "type":
            return True
        if e.validator in ("anyOf", "oneOf") and e.context and not _fitting_branches(e):
            return True
    return False


def _fitting_branches(err: ValidationError) -> list[list[ValidationError]]:
    """The failing branches of an anyOf/oneOf whose type matched the instance."""
    branches: dict = {}
    for e in err.context:
        branches.setdefault(e.relative_schema_path[0], []).append(e)
    depth = len(err.absolute_path)
    return [errs for errs in branches.values() if not _type_fails(errs, depth)]


def _convert(err: ValidationError, file: str, prefix: str) -> SessionError:
    """One ValidationError → SessionError(message, file, json path, hint)."""
    path = list(err.absolute_path)
    where = json_path(path, prefix)
    v, inst, sch = err.validator, err.instance, err.schema
    if v in ("oneOf", "anyOf"):
        choice = _only_required(err.validator_value)
        if choice is not None and not isinstance(inst, dict):
            return SessionError(f"expected an object, got {_got(inst)}", file, where or None, None)
        if choice is not None:
            present = [k for k in choice if k in inst]
            names = " or ".join(repr(k) for k in choice)
            msg = (f"give only one of {names}, not both" if len(present) > 1
                   else f"needs one of {names}")
            return SessionError(msg, file, where or None, None)
        fitting = _fitting_branches(err)
        if len(fitting) == 1:
            return _convert(_pick(fitting[0]), file, prefix)
        desc = sch.get("description") or " or ".join(
            sorted({_TYPE_NAMES.get(e.validator_value, str(e.validator_value)) for e in err.context
                    if e.validator == "type" and isinstance(e.validator_value, str)}))
        if not desc:
            return SessionError(err.message, file, where or None, None)
        return SessionError(f"expected {desc}, got {_got(inst)}", file, where or None, None)
    if v == "additionalProperties" and isinstance(inst, dict):
        known = set(sch.get("properties", {}))
        patterns = list(sch.get("patternProperties", {}))
        extra = [k for k in inst if k not in known and not any(re.search(p, k) for p in patterns)]
        key = extra[0] if extra else "?"
        keys = _valid_keys(sch)
        if patterns and not keys:
            return SessionError(f"{key!r} is not a valid GLSL identifier", file, json_path(path + [key], prefix),
                                "names must match [A-Za-z_][A-Za-z0-9_]*")
        close = difflib.get_close_matches(key, keys, n=1, cutoff=0.5)
        hint = (f"did you mean {close[0]!r}? " if close else "") + "valid keys: " + ", ".join(keys)
        return SessionError(f"unknown key {key!r}", file, json_path(path + [key], prefix), hint)
    if v == "required":
        missing = [k for k in err.validator_value if isinstance(inst, dict) and k not in inst]
        key = missing[0] if missing else err.validator_value[0]
        return SessionError(f"missing required key {key!r}", file, where or None, None)
    if v == "type":
        want = err.validator_value
        want = " or ".join(_TYPE_NAMES.get(w, w) for w in ([want] if isinstance(want, str) else want))
        return SessionError(f"expected {want}, got {_got(inst)}", file, where or None, None)
    if v in ("enum", "const"):
        options = err.validator_value if v == "enum" else [err.validator_value]
        hint = None
        if isinstance(inst, str):
            close = difflib.get_close_matches(inst, [str(o) for o in options], n=1, cutoff=0.5)
            hint = f"did you mean {close[0]!r}?" if close else None
        return SessionError(f"{_show(inst)} is not one of {', '.join(_show(o) for o in options)}",
                            file, where or None, hint)
    if v in ("minItems", "maxItems") and isinstance(inst, list):
        if sch.get("minItems") == sch.get("maxItems"):
            return SessionError(f"expected {sch['minItems']} items, got {len(inst)}", file, where or None, None)
        bound = "at least" if v == "minItems" else "at most"
        return SessionError(f"expected {bound} {err.validator_value} items, got {len(inst)}", file, where or None, None)
    if v == "items" and err.validator_value is False and isinstance(inst, list):
        n = len(sch.get("prefixItems", []))
        return SessionError(f"expected {n} items, got {len(inst)}", file, where or None, None)
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        rel = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}[v]
        return SessionError(f"{_show(inst)} must be {rel} {err.validator_value}", file, where or None, None)
    if v == "minLength":
        return SessionError("must not be empty", file, where or None, None)
    return SessionError(err.message, file, where or None, None)


def _hinted(error: SessionError, err: ValidationError) -> SessionError:
    """``error`` with a hint when it has none: what the schema says about the value (its
    description), and where the format is written down."""
    if error.hint:
        return error
    sch = err.schema if isinstance(err.schema, dict) else {}
    if err.validator == "required" and isinstance(err.instance, dict):
        key = next((k for k in err.validator_value if k not in err.instance), None)
        sch = sch.get("properties", {}).get(key, {}) if key is not None else {}
    desc = sch.get("description") if isinstance(sch, dict) else None
    hint = (f"{desc}; " if desc else "") + "the session format is rrcache/session/schema.json"
    return SessionError(error.message, error.path, error.json_path, hint)


def validate_document(doc: Any, file: str) -> None:
    """Raise SessionError for the best schema violation of the whole session ``doc``."""
    err = max(_validator(None).iter_errors(doc), key=relevance, default=None)
    if err is not None:
        raise _hinted(_convert(err, file, ""), err)


def validate_fragment(value: Any, definition: str, file: str, prefix: str) -> None:
    """Validate ``value`` against ``$defs/<definition>``; paths in errors start with ``prefix``."""
    err = max(_validator(definition).iter_errors(value), key=relevance, default=None)
    if err is not None:
        raise _hinted(_convert(err, file, prefix), err)
