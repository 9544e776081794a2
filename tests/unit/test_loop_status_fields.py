"""The type checker's view of :class:`harness.loop.status.LoopStatus` matches its field tables.

``LoopStatus`` gets one property per entry of ``NUMBER_FIELDS`` and ``TEXT_FIELDS``, installed
after the class; for mypy the class declares them again under ``if TYPE_CHECKING:``. This test
reads those declarations from the source (:mod:`ast`) so the two lists cannot drift apart.
"""

from __future__ import annotations

import ast
import inspect

from harness.loop import status


def _declared_fields() -> dict[str, str]:
    """``name -> type`` of every ``name = _Field[type]()`` in LoopStatus's ``if TYPE_CHECKING:`` block."""
    tree = ast.parse(inspect.getsource(status))
    (cls,) = [node for node in tree.body if isinstance(node, ast.ClassDef) and node.name == "LoopStatus"]
    blocks = [node for node in cls.body if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"]
    assert len(blocks) == 1, "LoopStatus declares its fields in one `if TYPE_CHECKING:` block"
    declared = {}
    for node in blocks[0].body:
        assert isinstance(node, ast.Assign) and isinstance(node.value, ast.Call), ast.unparse(node)
        factory = node.value.func
        assert isinstance(factory, ast.Subscript) and ast.unparse(factory.value) == "_Field", ast.unparse(node)
        (target,) = node.targets
        assert isinstance(target, ast.Name)
        declared[target.id] = ast.unparse(factory.slice)
    return declared


def test_every_field_is_declared_with_the_type_it_reads_back_as() -> None:
    expected = {name: "int" if is_integer else "float" for name, is_integer, _ in status.NUMBER_FIELDS}
    expected |= {name: "str" for name, _, _ in status.TEXT_FIELDS}
    assert _declared_fields() == expected


def test_the_declared_fields_read_back_as_their_types() -> None:
    with status.LoopStatus() as loop_status:
        for name, kind in _declared_fields().items():
            assert type(getattr(loop_status, name)).__name__ == kind, name
