"""YAML that refuses a key given twice in one mapping.

PyYAML's ``safe_load`` keeps the last of two equal keys without a word, so a profile with a
second ``safety:`` section silently replaced the first and its stroke limits fell back to
the code's defaults. :func:`load_unique` parses with the safe loader but raises
:class:`DuplicateKeyError`, with the line of both occurrences, instead.

Merge keys (``<<: *base``) still work: keys brought in by a merge may be overridden by the
mapping's own keys, as YAML intends; only two explicit equal keys are refused.
"""

from __future__ import annotations

from typing import Any

import yaml

_MERGE_TAG = "tag:yaml.org,2002:merge"


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


class UniqueKeyLoader(yaml.SafeLoader):
    """The safe loader, refusing a mapping that gives one key twice."""

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
    """Parse YAML ``text`` like ``yaml.safe_load``, refusing duplicate keys.

    Raises
    ------
    DuplicateKeyError
        For a key given twice in one mapping (a :class:`yaml.YAMLError`).
    yaml.YAMLError
        For anything else that is not valid YAML.
    """
    return yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
