"""pybind11's own signatures of simloop._core (the docstrings it writes, which
mypy's stubtest cannot read) against the stub python/simloop/_core.pyi:
_compare(_Stub(path)) lists each difference with the stub line the module's
signature suggests. Used by test_types.py."""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path
from typing import Dict, List, Optional, Tuple

from simloop import _core

# ---- pybind11's signatures against the stub's --------------------------------


def _split_top(text: str, sep: str = ",") -> List[str]:
    """text split at `sep` outside brackets and quotes."""
    parts, depth, quote, start = [], 0, "", 0
    i = 0
    while i < len(text):
        c = text[i]
        if quote:
            if c == "\\":
                i += 1
            elif c == quote:
                quote = ""
        elif c in "'\"":
            quote = c
        elif c in "[(":
            depth += 1
        elif c in "])":
            depth -= 1
        elif depth == 0 and text.startswith(sep, i):
            parts.append(text[start:i])
            start = i + len(sep)
            i += len(sep)
            continue
        i += 1
    parts.append(text[start:])
    return [p.strip() for p in parts if p.strip()]


# One parameter: (name, positional_only, type text, default text or None).
Param = Tuple[str, bool, str, Optional[str]]
Signature = Tuple[List[Param], str]  # parameters (without self), return type text


def _pybind_signatures(name: str, doc: Optional[str], method: bool) -> List[Signature]:
    """The signatures pybind11 wrote into a function's docstring (several if overloaded)."""
    lines = (doc or "").splitlines()
    if len(lines) > 1 and lines[1].strip() == "Overloaded function.":
        heads = [line.split(". ", 1)[1] for line in lines if re.match(r"^\d+\. ", line)]
    else:
        heads = lines[:1]
    signatures = []
    for head in heads:
        match = re.match(r"^\s*" + re.escape(name) + r"\((.*)\) -> (.*)$", head) or re.match(
            r"^\s*\((.*)\) -> (.*)$", head
        )  # a property's getter: "(arg0: X) -> T"
        if not match:
            raise AssertionError(f"cannot read pybind11's signature of {name}: {head!r}")
        params: List[Param] = []
        for text in _split_top(match.group(1)):
            parts = _split_top(text, " = ")
            text, default = parts[0], (parts[1] if len(parts) > 1 else None)
            pname, _, ptype = text.partition(": ")
            params.append((pname, bool(re.fullmatch(r"arg\d+", pname)), ptype or "object", default))
        if method and params:
            params = params[1:]  # self
        signatures.append((params, match.group(2).strip()))
    return signatures


class _Stub:
    """The stub's signatures, read with ast: {"name" or "Class.name": (kind, [Signature])}."""

    def __init__(self, path: Path) -> None:
        tree = ast.parse(path.read_text())
        self.aliases: Dict[str, ast.expr] = {}
        self.typed_dicts = set()
        self.entries: Dict[str, Tuple[str, List[Signature], bool]] = {}
        for node in tree.body:
            if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name):
                self.aliases[node.targets[0].id] = node.value
            elif isinstance(node, ast.ClassDef):
                if any(isinstance(b, ast.Name) and b.id == "TypedDict" for b in node.bases):
                    self.typed_dicts.add(node.name)
                    continue
                self.entries[node.name] = ("class", [], False)
                for item in node.body:
                    if isinstance(item, ast.FunctionDef):
                        self._add(f"{node.name}.{item.name}", item, method=True)
            elif isinstance(node, ast.FunctionDef):
                self._add(node.name, node, method=False)

    def _add(self, key: str, f: ast.FunctionDef, method: bool) -> None:
        decorators = {ast.unparse(d) for d in f.decorator_list}
        if any(d.endswith(".setter") for d in decorators):
            kind, signatures, _ = self.entries[key]
            self.entries[key] = (kind, signatures, True)
            return
        kind = (
            "property"
            if "property" in decorators
            else "staticmethod"
            if "staticmethod" in decorators
            else ("method" if method else "function")
        )
        args = f.args
        positional = args.posonlyargs + args.args
        defaults = [None] * (len(positional) - len(args.defaults)) + list(args.defaults)
        params: List[Param] = []
        for i, (a, d) in enumerate(zip(positional, defaults)):
            params.append(
                (
                    a.arg,
                    i < len(args.posonlyargs) or a.arg.startswith("__"),
                    ast.unparse(a.annotation) if a.annotation else "object",
                    None if d is None else ast.unparse(d),
                )
            )
        if args.vararg:  # pybind11's py::args: "*args: object"; a stub may say Never (none may be given)
            annotation = ast.unparse(args.vararg.annotation) if args.vararg.annotation else "object"
            params.append(("*" + args.vararg.arg, False, "object" if annotation == "Never" else annotation, None))
        for a, d in zip(args.kwonlyargs, args.kw_defaults):
            params.append(
                (
                    a.arg,
                    False,
                    ast.unparse(a.annotation) if a.annotation else "object",
                    None if d is None else ast.unparse(d),
                )
            )
        if method and kind != "staticmethod":
            params = params[1:]
        signature = (params, ast.unparse(f.returns) if f.returns else "None")
        previous = self.entries.get(key)
        if previous and "overload" in decorators:
            previous[1].append(signature)
        else:
            self.entries[key] = (kind, [signature], False)


# A type, canonical: "*" matches anything; a frozenset is a union; (name, args) otherwise.
def _canonical(expr: ast.expr, stub: Optional[_Stub]):
    def name_of(node: ast.expr) -> str:
        text = ast.unparse(node)
        for prefix in (
            "typing.",
            "collections.abc.",
            "simloop._core.",
            "numpy.typing.",
            "pathlib.",
            "os.",
            "np.",
            "numpy.",
        ):
            if text.startswith(prefix):
                text = text[len(prefix) :]
        return text

    def go(node: ast.expr):
        if isinstance(node, ast.Constant):
            if node.value is None:
                return ("None", ())
            if node.value is Ellipsis:
                return "*"
            if isinstance(node.value, str):  # a forward reference
                return go(ast.parse(node.value, mode="eval").body)
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitOr):
            return union([go(node.left), go(node.right)])
        if isinstance(node, ast.Subscript):
            base = name_of(node.value)
            items = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
            if base in ("Optional",):
                return union([go(items[0]), ("None", ())])
            if base == "Union":
                return union([go(i) for i in items])
            if base in ("Annotated", "Final"):
                return go(items[0])
            if base in ("NDArray", "ndarray"):
                return ("ndarray", ())
            if base in ("Callable", "Literal", "PathLike"):
                return (base if base != "Literal" else "str", ())
            return (base, tuple(go(i) for i in items))
        name = name_of(node)
        if stub is not None and name in stub.aliases:
            return go(stub.aliases[name])
        if stub is not None and name in stub.typed_dicts:
            return ("dict", ())
        if name in ("object", "Any") or "::" in name:
            return "*"
        return (name, ())

    def union(members):
        flat = set()
        for m in members:
            flat |= set(m) if isinstance(m, frozenset) else {m}
        if "*" in flat:
            return "*"
        names = {m[0] for m in flat}
        # pybind11's spellings of what Python's int, float and os.PathLike arguments accept
        for supports, plain in (
            ({"SupportsInt", "SupportsIndex"}, "int"),
            ({"SupportsFloat", "SupportsIndex"}, "float"),
        ):
            if supports <= names:
                flat = {m for m in flat if m[0] not in supports} | {(plain, ())}
                names = {m[0] for m in flat}
        if {"PathLike", "str", "bytes"} <= names:
            flat = {m for m in flat if m[0] not in ("PathLike", "str", "bytes")} | {("path", ())}
        return next(iter(flat)) if len(flat) == 1 else frozenset(flat)

    return go(expr)


def _parse_type(text: str, stub: Optional[_Stub]):
    text = re.sub(r"[A-Za-z_][\w]*(?:::[\w]+)+", "object", text)  # a C++ type pybind11 could not name
    return _canonical(ast.parse(text, mode="eval").body, stub)


def _same(a, b) -> bool:
    if a == "*" or b == "*":
        return True
    if isinstance(a, frozenset) or isinstance(b, frozenset):
        a_set = a if isinstance(a, frozenset) else frozenset([a])
        b_set = b if isinstance(b, frozenset) else frozenset([b])
        return all(any(_same(x, y) for y in b_set) for x in a_set) and all(
            any(_same(y, x) for x in a_set) for y in b_set
        )
    if a[0] != b[0]:
        return False
    if not a[1] or not b[1]:
        return True  # pybind11 writes a bare `dict`, `tuple`, `list`
    return len(a[1]) == len(b[1]) and all(_same(x, y) for x, y in zip(a[1], b[1]))


def _stub_text(type_text: str) -> str:
    """pybind11's type text in the stub's words (for the suggested line)."""
    text = re.sub(r"typing\.Annotated\[(.*?), \"[^\"]*\"\]", r"\1", type_text)
    text = text.replace("typing.SupportsInt | typing.SupportsIndex", "int")
    text = text.replace("typing.SupportsFloat | typing.SupportsIndex", "float")
    text = text.replace("os.PathLike | str | bytes", "_PathLike").replace("numpy.ndarray", "_Float64Array")
    text = re.sub(r"\b(simloop\._core|typing|collections\.abc|pathlib)\.", "", text)
    return re.sub(r"[A-Za-z_]\w*(?:::\w+)+", "object", text)


def _suggest(name: str, kind: str, signatures: List[Signature]) -> str:
    out = []
    for params, returns in signatures:
        args = ["self"] if kind in ("method", "property") else []
        for pname, _positional_only, ptype, default in params:
            args.append(f"{pname}: {_stub_text(ptype)}" + (f" = {default}" if default is not None else ""))
        last_positional_only = max((i for i, p in enumerate(params) if p[1]), default=None)
        if last_positional_only is not None:  # pybind11's unnamed arguments (arg0, ...)
            args.insert(len(args) - len(params) + last_positional_only + 1, "/")
        prefix = {"property": "@property ", "staticmethod": "@staticmethod "}.get(kind, "")
        overload = "@overload " if len(signatures) > 1 else ""
        out.append(f"{overload}{prefix}def {name.split('.')[-1]}({', '.join(args)}) -> {_stub_text(returns)}: ...")
    return " | ".join(out)


def _runtime_entries():
    """(qualified name, kind, pybind11 signatures, writable) of every compiled function, method, property."""

    def compiled(f: object) -> bool:
        return type(f).__name__ == "builtin_function_or_method"

    for name, obj in sorted(vars(_core).items()):
        if name.startswith("_"):
            continue
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            init = vars(obj).get("__init__")
            if init is not None and compiled(getattr(init, "__func__", None)):
                yield f"{name}.__init__", "method", _pybind_signatures("__init__", init.__doc__, True), False
            elif init is None:
                yield f"{name}.__init__", "none", [], False
            for attr, member in sorted(vars(obj).items()):
                if attr.startswith("_"):
                    continue
                key = f"{name}.{attr}"
                if isinstance(member, property):
                    if compiled(member.fget):
                        yield (
                            key,
                            "property",
                            _pybind_signatures(attr, member.fget.__doc__, True),
                            member.fset is not None,
                        )
                elif isinstance(member, staticmethod):
                    if compiled(member.__func__):
                        yield key, "staticmethod", _pybind_signatures(attr, member.__func__.__doc__, False), False
                elif compiled(getattr(member, "__func__", None)):
                    yield key, "method", _pybind_signatures(attr, member.__doc__, True), False
        elif compiled(obj):
            yield name, "function", _pybind_signatures(name, obj.__doc__, False), False


def _compare(stub: _Stub) -> List[str]:
    problems = []
    for key, kind, signatures, writable in _runtime_entries():
        entry = stub.entries.get(key)
        if kind == "none":  # no py::init: pybind11's __init__ raises TypeError
            if entry is not None:
                problems.append(f"{key}: the stub has a constructor; the module has none (no py::init): remove it")
            continue
        if key.split(".")[0] not in stub.entries and "." in key:
            continue  # the whole class is missing: reported once, below
        if entry is None:
            problems.append(f"{key}: missing from the stub; the module has: {_suggest(key, kind, signatures)}")
            continue
        stub_kind, stub_signatures, stub_writable = entry
        want = _suggest(key, kind, signatures)
        if stub_kind != kind and not (kind == "method" and key.endswith(".__init__")):
            problems.append(f"{key}: a {kind} in the module, a {stub_kind} in the stub; the module has: {want}")
            continue
        if writable != stub_writable:
            problems.append(
                f"{key}: {'writable' if writable else 'read-only'} in the module, "
                f"{'writable' if stub_writable else 'read-only'} in the stub"
                + (" (add a @" + key.split(".")[-1] + ".setter)" if writable else "")
            )
        if len(signatures) != len(stub_signatures):
            problems.append(
                f"{key}: {len(signatures)} overload(s) in the module, {len(stub_signatures)} in the stub; "
                f"the module has: {want}"
            )
            continue
        for (params, returns), (stub_params, stub_returns) in zip(signatures, stub_signatures):
            differences = []
            if [p[0] for p in params if not p[1]] != [p[0] for p in stub_params if not p[1]] or [
                p[1] for p in params
            ] != [p[1] for p in stub_params]:
                differences.append(
                    f"parameters ({', '.join(p[0] for p in params)}) in the module, "
                    f"({', '.join(p[0] for p in stub_params)}) in the stub"
                )
            else:
                for (pname, _, ptype, default), (_, _, stype, sdefault) in zip(params, stub_params):
                    if default == "None" and not re.search(r"\bNone\b", ptype):
                        ptype += " | None"  # pybind11 passes None as a null pointer, and says so only here
                    if not _same(_parse_type(ptype, None), _parse_type(stype, stub)):
                        differences.append(f"{pname}: {ptype} in the module, {stype} in the stub")
                    if (default is None) != (sdefault is None):
                        differences.append(f"{pname}: default {default} in the module, {sdefault} in the stub")
                    elif default is not None and sdefault != "...":
                        try:
                            if ast.literal_eval(default) != ast.literal_eval(sdefault):
                                differences.append(f"{pname}: default {default} in the module, {sdefault} in the stub")
                        except (ValueError, SyntaxError):
                            pass  # not a literal (an object's repr): its presence is what can be compared
            if not key.endswith(".__init__") and not _same(_parse_type(returns, None), _parse_type(stub_returns, stub)):
                differences.append(f"returns {returns} in the module, {stub_returns} in the stub")
            if differences:
                problems.append(f"{key}: " + "; ".join(differences) + f"; the module has: {want}")
    for name, obj in sorted(vars(_core).items()):
        if inspect.isclass(obj) and not name.startswith("_") and name not in stub.entries:
            problems.append(f"{name}: a class missing from the stub: class {name}(metaclass=_Pybind11Type): ...")
    return problems
