"""The sections of a profile that the control's factory reads, as a structural type.

:mod:`harness.control.factory` and :mod:`harness.control.estimator_margin` build controllers,
estimators and compensators from these sections alone, so the control package never imports the
profile that puts every section together (:mod:`harness.profile` imports the control's settings:
the other way round would be a ring). A :class:`~harness.profile.Profile` is one; so is anything
with these attributes.
"""

from __future__ import annotations

from typing import Protocol

from harness.control.config import ControlConfig
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.rig.config import RigConfig
from harness.safety.config import SafetyConfig


class ControlSections(Protocol):
    """What the factory reads: the design building and bearing, the control, the rig's actuator, the force limits."""

    @property
    def structure(self) -> BuildingConfig:
        """The design building (SPEC 1)."""

    @property
    def bearing(self) -> BearingConfig:
        """The design bearing (SPEC 2)."""

    @property
    def control(self) -> ControlConfig:
        """Designs, compensation and the estimator (SPEC 3)."""

    @property
    def rig(self) -> RigConfig:
        """The rig: its actuator model and physics sub-step."""

    @property
    def safety(self) -> SafetyConfig:
        """The safety settings (the force-tracking tolerance bounds the model compensation)."""

    @property
    def source_path(self) -> str:
        """The file the sections came from, for the errors that name a key."""
