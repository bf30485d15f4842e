"""The skip rule's classes declare their state in ``__init__`` (issue 26, item 3).

What a start or a batch computes is a frozen record returned by the function
that computes it; an object holds it in an attribute declared in ``__init__``.
This test reads ``checker/advance/*.py`` with :mod:`ast` and fails on any
class whose methods assign an attribute of ``self`` that ``__init__`` does not
(dataclass fields and properties count as declared). Reassigning a declared
attribute, or changing a declared array in place, is allowed.
"""

from __future__ import annotations

import ast
from pathlib import Path

ADVANCE = Path(__file__).resolve().parents[1] / "checker" / "advance"


def _stored(node: ast.AST) -> set[str]:
    """Names of ``self`` attributes a function assigns (``self.x = ``,
    ``self.x += ``, ``self.x: T = ``, tuple targets, and ``setattr(self,
    "x", ...)``), nested functions included."""
    out = set()
    for n in ast.walk(node):
        if isinstance(n, ast.Attribute) and isinstance(n.ctx, ast.Store) \
                and isinstance(n.value, ast.Name) and n.value.id == "self":
            out.add(n.attr)
        elif isinstance(n, ast.Call) and isinstance(n.func, (ast.Name, ast.Attribute)) \
                and (n.func.id if isinstance(n.func, ast.Name) else n.func.attr) in ("setattr", "__setattr__") \
                and len(n.args) >= 2 and isinstance(n.args[0], ast.Name) and n.args[0].id == "self" \
                and isinstance(n.args[1], ast.Constant) and isinstance(n.args[1].value, str):
            out.add(n.args[1].value)
    return out


def _is_property(fn: ast.FunctionDef) -> bool:
    """A method decorated as a property (or a property's setter)."""
    for d in fn.decorator_list:
        if isinstance(d, ast.Name) and d.id in ("property", "cached_property"):
            return True
        if isinstance(d, ast.Attribute) and d.attr in ("setter", "cached_property"):
            return True
    return False


def undeclared(source: str) -> list[tuple[str, str, str]]:
    """(class, method, attribute) for every attribute of ``self`` a method
    other than ``__init__`` assigns that ``__init__`` does not, that is no
    dataclass field (an annotated name in the class body) and no property."""
    found = []
    for cls in (n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.ClassDef)):
        methods = [f for f in cls.body if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))]
        declared = {t.target.id for t in cls.body if isinstance(t, ast.AnnAssign) and isinstance(t.target, ast.Name)}
        declared |= {f.name for f in methods if _is_property(f)}
        for f in methods:
            if f.name == "__init__":
                declared |= _stored(f)
        for f in methods:
            if f.name != "__init__":
                found += [(cls.name, f.name, a) for a in sorted(_stored(f) - declared)]
    return found


def test_the_check_finds_an_attribute_set_outside_init():
    """The check is not vacuous: a method's new attribute, a tuple target, a
    setattr and an augmented assignment are found; declared names,
    properties and dataclass fields are not."""
    source = '''
class A:
    x: int
    def __init__(self):
        self.a = None
    @property
    def p(self):
        return 1
    def start(self):
        self.a = 1
        self.x = 2
        self.b = 3
        self.c, (self.d, _) = 4, (5, 6)
        setattr(self, "e", 7)
        self.f += 1
        def inner():
            self.g = 8
'''
    got = {a for _, _, a in undeclared(source)}
    assert got == {"b", "c", "d", "e", "f", "g"}


def test_skip_rule_classes_declare_their_state_in_init():
    """No class of checker/advance sets an attribute first outside ``__init__``."""
    files = sorted(ADVANCE.glob("*.py"))
    assert len(files) >= 5
    found = [(f.name, *hit) for f in files for hit in undeclared(f.read_text())]
    assert not found, "attributes set outside __init__ (declare them there): " + ", ".join(
        f"{file}:{cls}.{method} sets self.{attr}" for file, cls, method, attr in found)
