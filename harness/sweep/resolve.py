"""A case's profile: the study's base profile with the case's ``--set`` overrides, validated like the file.

``load_profile(path, variant, overrides)`` reads and parses the YAML and builds the whole profile
and every variant again (about 40 ms for the eight-story profile), which is a fifth of a short
case. A sweep loads its base profile once per process (:func:`base_profile`) and applies each
case's overrides with :func:`case_profile`: the sections an override touches are rebuilt by the
same schema builder from the base values merged with the overrides, and the profile's own
cross-section checks run again (``dataclasses.replace`` calls ``__post_init__``). For the
sections below that is what ``load_profile`` does; an override of any other section (safety,
CAN, rig, loop, table limits) takes the full path, ``load_profile`` itself, whose extra checks
(force ceilings, safety weakening) concern those sections. ``tests/unit/test_sweep_resolve.py``
checks that both paths give equal profiles.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any, get_type_hints

from harness.config.schema import build, to_data
from harness.errors import ProfileError
from harness.profile import Profile, load_profile, merge, parse_overrides

#: Sections rebuilt on their own: plain configuration whose checks are all in their dataclasses.
FAST_SECTIONS = frozenset({"structure", "bearing", "control", "record", "simulation"})


@dataclass(frozen=True)
class BaseProfile:
    """Where the study's base profile comes from: the file, a variant and the study's own ``set``.

    Plain strings, so that it travels to worker processes and Dask workers.
    """

    path: str
    variant: str | None = None
    overrides: tuple[str, ...] = ()
    overlay: str | None = None

    def load(self) -> Profile:
        """The base profile, loaded once per process (:func:`base_profile`)."""
        return base_profile(self.path, self.variant, self.overrides, self.overlay)


@functools.lru_cache(maxsize=8)
def base_profile(path: str, variant: str | None, overrides: tuple[str, ...], overlay: str | None = None) -> Profile:
    """``load_profile(path, variant, overrides, overlay)``, cached for the life of the process."""
    return load_profile(path, variant=variant, overrides=list(overrides), overlay=overlay)


@functools.lru_cache(maxsize=1)
def _section_types() -> dict[str, Any]:
    return get_type_hints(Profile)


def case_profile(base: BaseProfile, overrides: tuple[str, ...]) -> Profile:
    """The profile of one case: the base profile with ``overrides`` (``KEY.PATH=VALUE``) applied last.

    Parameters
    ----------
    base : BaseProfile
    overrides : tuple of str
        The case's own overrides, over the base's (``--set`` order: later wins, each key once).

    Returns
    -------
    Profile
        Equal to ``load_profile(base.path, base.variant, base.overrides + overrides, base.overlay)``.

    Raises
    ------
    ProfileError
        As ``load_profile`` would, naming the key, what was found and what was expected.
    """
    profile = base.load()
    if not overrides:
        return profile
    changes = parse_overrides(overrides)
    if not set(changes) <= FAST_SECTIONS or not all(isinstance(change, dict) for change in changes.values()):
        return load_profile(base.path, variant=base.variant, overrides=[*base.overrides, *overrides], overlay=base.overlay)
    source = f"{base.path} (with --set {' '.join(overrides)})"
    types = _section_types()
    sections = {
        name: build(types[name], merge(to_data(getattr(profile, name)), change), source=source, path=name)
        for name, change in changes.items()
    }
    try:
        return dataclasses.replace(profile, **sections)
    except ValueError as err:  # a cross-section check of the profile, as it would fail from the file
        raise ProfileError(str(err), source) from err
