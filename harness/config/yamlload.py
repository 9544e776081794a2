"""YAML that refuses a key given twice in one mapping, and documents too large or too deep to be input.

PyYAML's ``safe_load`` keeps the last of two equal keys without a word, so a profile with a
second ``safety:`` section silently replaced the first and its stroke limits fell back to
the code's defaults. :func:`load_unique` parses with the safe loader but raises
:class:`DuplicateKeyError`, with the line of both occurrences, instead.

Merge keys (``<<: *base``) still work: keys brought in by a merge may be overridden by the
mapping's own keys, as YAML intends; only two explicit equal keys are refused.

Every profile, ``--set`` value and study file goes through :func:`load_unique`, so the limits
on what a YAML document may be are kept here, once, and refused with :class:`YamlLimitError`
(a :class:`yaml.YAMLError`, reported as invalid YAML with the limit's name and value):

- :data:`MAX_YAML_CHARS`, the length of the text;
- :data:`MAX_DEPTH`, lists and mappings inside each other, as written and as the aliases
  expand them (500 nested ``[`` in a 1 kB file overflowed the interpreter's stack);
- :data:`MAX_VALUES`, the values of the document once its aliases are expanded: an alias
  stands for the whole node it names, so nine lines of aliases of aliases stand for a
  billion strings (an "alias bomb"). PyYAML builds such a document cheaply, sharing the
  repeated objects, but everything that walks it afterwards (a message quoting a value, a
  deep copy, the resolved profile written to a run folder) pays for every copy;
- recursive aliases (an anchor used inside its own node), which no walk ends.

The aliases are counted on the composed node graph, before any Python object is built:
each distinct node is visited once, so the count of the expanded document costs as much
as reading the text, whatever it expands to.
"""

from __future__ import annotations

from typing import Any

import yaml

_MERGE_TAG = "tag:yaml.org,2002:merge"

#: Longest YAML text read (characters; a file is also refused beyond this many bytes). The
#: shipped profiles are 3-21 kB (the rig profile, with the derivations of its values in comments) and
#: the studies about 1 kB: fifty times the largest leaves room for any hand-written file while a
#: mistaken file (a log, a data set) is refused at once.
MAX_YAML_CHARS = 1_000_000

#: Deepest nesting of values (the top-level mapping is level 1, a value in it level 2, ...). The shipped
#: profiles and studies reach 5-7 levels (``variants.NAME.control.designs.NAME.KEY``). Every
#: level costs the loader and the code that walks the data a few Python frames (composing,
#: constructing, the schema's ``build``, the deep copy of a merge: 3 to 6 each), so 32 levels,
#: four times the deepest file, stay within about 200 frames, far from the interpreter's
#: recursion limit of 1000 wherever the caller's stack stands.
MAX_DEPTH = 32

#: Most values (scalars, lists and mappings, keys included) of a document with its aliases
#: expanded. The shipped profiles hold 260 at most and a study's longest list (an axis, a
#: ``pga_levels`` range) takes 1000 values (``harness.sweep.study.MAX_LEVELS``): 100,000 is a
#: hundred times that, and walking so many values takes well under a second, while a
#: billion-value alias bomb is refused before it is built.
MAX_VALUES = 100_000


class DuplicateKeyError(yaml.constructor.ConstructorError):
    """A mapping holds the same key twice.

    Attributes
    ----------
    key : object
        The repeated key.
    first, second : yaml.Mark
        Where the first and the second occurrence start (``line`` and ``column`` are 0-based).
    """

    def __init__(self, key: Any, first: yaml.Mark, second: yaml.Mark):
        self.key = key
        self.first = first
        self.second = second
        super().__init__(
            None, None,
            f"duplicate key {key!r} at line {second.line + 1}, column {second.column + 1} "
            f"(first at line {first.line + 1}, column {first.column + 1}); expected each key once per mapping, "
            "since the second would silently replace the first",
            second,
        )

    def describe(self) -> str:
        """The message without PyYAML's mark excerpt."""
        return str(self.problem)


class YamlLimitError(yaml.composer.ComposerError):
    """A YAML document beyond one of the limits of this module (its size, depth or expanded values).

    The message names the limit and says what was found; ``problem_mark`` is where, when known.
    """

    def __init__(self, problem: str, mark: yaml.Mark | None = None):
        super().__init__(None, None, problem, mark)


def _children(node: yaml.Node) -> list[yaml.Node]:
    """The nodes directly inside ``node``: a list's items, a mapping's keys and values."""
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [item for pair in node.value for item in pair]
    return []


def check_expansion(root: yaml.Node) -> tuple[int, int]:
    """Count the values and levels of a composed document as its aliases expand it.

    Each distinct node is visited once and its figures are remembered, so a node that
    aliases repeat costs nothing more; the walk stops at the first limit passed, so it never
    goes deeper than :data:`MAX_DEPTH` frames.

    Parameters
    ----------
    root : yaml.Node
        The document's root node, as composed (aliases are the very node they name).

    Returns
    -------
    values, depth : int
        Values of the expanded document and its deepest level (the root is level 1).

    Raises
    ------
    YamlLimitError
        Beyond :data:`MAX_VALUES` or :data:`MAX_DEPTH`, or for an anchor used inside itself.
    """
    figures: dict[int, tuple[int, int]] = {}  # id(node) -> (values, height)
    open_nodes: set[int] = set()

    def visit(node: yaml.Node, level: int) -> tuple[int, int]:
        key = id(node)
        known = figures.get(key)
        if known is None:
            if key in open_nodes:
                raise YamlLimitError(
                    "an alias refers to the node that holds it (a recursive anchor); expected a document "
                    "that ends, with each alias outside the node its anchor names", node.start_mark,
                )
            if level > MAX_DEPTH:
                raise YamlLimitError(
                    f"values nested deeper than {MAX_DEPTH} levels once the aliases are expanded; "
                    f"expected at most {MAX_DEPTH} (MAX_DEPTH)", node.start_mark,
                )
            open_nodes.add(key)
            values, height = 1, 1
            for child in _children(node):
                child_values, child_height = visit(child, level + 1)
                values += child_values
                height = max(height, child_height + 1)
                if values > MAX_VALUES:
                    break
            open_nodes.discard(key)
            known = figures[key] = (values, height)
        values, height = known
        if level + height - 1 > MAX_DEPTH:
            raise YamlLimitError(
                f"values nested {level + height - 1} levels deep once the aliases are expanded; "
                f"expected at most {MAX_DEPTH} (MAX_DEPTH)", node.start_mark,
            )
        if values > MAX_VALUES:
            raise YamlLimitError(
                f"the document holds more than {MAX_VALUES} values once its aliases (*name) are expanded; expected "
                f"at most {MAX_VALUES} (MAX_VALUES): each alias repeats the whole node its anchor (&name) names",
                node.start_mark,
            )
        return known

    return visit(root, 1)


class UniqueKeyLoader(yaml.SafeLoader):
    """The safe loader, refusing a mapping that gives one key twice, and documents beyond the limits."""

    _depth = 0

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node:
        """Compose one node, refusing nesting deeper than :data:`MAX_DEPTH` as written.

        Composing recurses once per level, so this check comes before the recursion does:
        the expanded depth is checked once the document is composed (:func:`check_expansion`).

        Raises
        ------
        YamlLimitError
            At the first node below level :data:`MAX_DEPTH`.
        """
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise YamlLimitError(
                    f"values nested deeper than {MAX_DEPTH} levels; expected at most {MAX_DEPTH} (MAX_DEPTH)",
                    self.peek_event().start_mark,
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def compose_document(self) -> yaml.Node:
        """Compose the document and check what its aliases expand to (:func:`check_expansion`)."""
        node = super().compose_document()
        check_expansion(node)
        return node

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        """Build the mapping after checking its explicit keys are unique.

        Raises
        ------
        DuplicateKeyError
            Naming the key and the lines of both occurrences.
        """
        if isinstance(node, yaml.MappingNode):
            seen: dict[Any, yaml.Mark] = {}
            for key_node, _ in node.value:
                if key_node.tag == _MERGE_TAG:
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    first = seen.get(key)
                except TypeError:  # an unhashable key: the base class refuses it with its own message
                    continue
                if first is not None:
                    raise DuplicateKeyError(key, first, key_node.start_mark)
                seen[key] = key_node.start_mark
        return super().construct_mapping(node, deep=deep)


def load_unique(text: str) -> Any:
    """Parse YAML ``text`` like ``yaml.safe_load``, refusing duplicate keys and documents beyond the limits.

    Raises
    ------
    DuplicateKeyError
        For a key given twice in one mapping (a :class:`yaml.YAMLError`).
    YamlLimitError
        For a text longer than :data:`MAX_YAML_CHARS`, nesting deeper than :data:`MAX_DEPTH`,
        more than :data:`MAX_VALUES` values once the aliases are expanded, or a recursive alias
        (a :class:`yaml.YAMLError`).
    yaml.YAMLError
        For anything else that is not valid YAML.
    """
    if len(text) > MAX_YAML_CHARS:
        raise YamlLimitError(f"the text is {len(text)} characters long; expected at most {MAX_YAML_CHARS} (MAX_YAML_CHARS)")
    return yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
