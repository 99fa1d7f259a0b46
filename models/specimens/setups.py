"""The test setup as part of the model: what a test attaches to the specimen.

One structure and one joint are tested several ways: a hammer test (free-free or clamped, a
few accelerometers), a shaker test (the shaker's moving parts, stinger and force gauge at the
drive point), a clamp that is never rigid. A :class:`Setup` declares these beside the
specimen (``Specimen.setup``); every analysis of that specimen (QSMA, harmonic balance,
nonlinear modes, the ring-down, the solid bodies) reads the specimen's linear system, which
includes it (:func:`~iwan_element.models.reduced.dispatch.linear_system`). The relations
(docs/equations.md section 12, docs/linear_update.md):

* :class:`PointMass`: a mass (and rotary inertia) on the beams' axis at a position: an
  accelerometer, the part of a force gauge below its sensing element, a fixture.
* :class:`Shaker` at the drive point: the force gauge measures the force above its sensing
  element, so the mass between the element and the structure (``gauge_mass``) is part of
  the structure ("mass cancellation"). Behind the gauge sit the stinger (axial stiffness)
  and the moving mass (armature, upper gauge), suspended by the shaker's flexures. What of
  it the model holds depends on which force the test knows (``force_at``):

  - ``"gauge"`` (a force-measured test, the usual one): the measured force acts on the
    structure; only ``gauge_mass`` is added. The stinger and moving mass are behind the
    measured force and cannot change the response to it: a target never sees them.
  - ``"armature"`` (a shaker driven by its amplifier, no gauge): the force acts on the
    moving mass, which is one more coordinate of the model, tied to the drive point by the
    stinger and to the ground by the suspension; ``gauge_mass`` rides on the structure.
  - ``"passive"`` (the shaker left on while another excitation acts, e.g. a hammer): the
    moving mass, stinger and suspension are in the model, the excitation acts on the
    structure.

* :class:`Clamp`: the root of a ``"clamped-free"`` beam held by springs instead of rigidly:
  a translational stiffness (axial and transverse) and a rotational one.

Every value has a physical range (``Setup.ranges``, or the defaults of
:func:`~iwan_element.models.updating.updatable`) that model updating uses as its prior.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from iwan_element.base.validation import plain_fields

__all__ = ["PointMass", "Shaker", "Clamp", "Setup", "FORCE_AT"]

FORCE_AT = ("gauge", "armature", "passive")


def _nonneg(name, v, *, positive=False):
    if (
        isinstance(v, bool)
        or not isinstance(v, (int, float))
        or not math.isfinite(float(v))
        or v < 0
        or (positive and v == 0)
    ):
        raise ValueError(f"{name} must be a finite number {'>' if positive else '>='} 0, got {v!r}")
    return float(v)


@dataclass(frozen=True)
class PointMass:
    """A mass on the beams' axis.

    Parameters
    ----------
    name : str
        Its name (an accelerometer's channel, ``"fixture"``, ...); the updating parameter is
        ``mass:<name>``.
    position : float
        Along the assembly [m] (the axis of ``Specimen.sensor_position``).
    mass : float
        [kg], >= 0.
    rotary_inertia : float
        About the width axis [kg m^2], >= 0 (1-D beams; the solid bodies take the mass only).
    """

    name: str
    position: float
    mass: float
    rotary_inertia: float = 0.0

    def __post_init__(self):
        plain_fields(self)
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name must be a non-empty string, got {self.name!r}")
        object.__setattr__(self, "position", _nonneg("position", self.position))
        object.__setattr__(self, "mass", _nonneg(f"mass of {self.name}", self.mass))
        object.__setattr__(
            self, "rotary_inertia", _nonneg(f"rotary_inertia of {self.name}", self.rotary_inertia)
        )


@dataclass(frozen=True)
class Shaker:
    """A shaker at the drive point (module docstring).

    Parameters
    ----------
    position : float
        Drive point along the assembly [m].
    gauge_mass : float
        Mass between the force gauge's sensing element and the structure [kg].
    moving_mass : float
        Armature, stinger and upper gauge [kg] (in the model for ``force_at`` "armature"
        and "passive").
    stinger_stiffness : float
        Axial stiffness of the stinger [N/m], > 0.
    suspension_stiffness : float
        The armature's flexures to the shaker body [N/m], >= 0.
    force_at : {"gauge", "armature", "passive"}
        Which force the test knows (module docstring).
    """

    position: float
    gauge_mass: float = 0.0
    moving_mass: float = 0.0
    stinger_stiffness: float = 1.0e6
    suspension_stiffness: float = 0.0
    force_at: str = "gauge"

    def __post_init__(self):
        plain_fields(self)
        object.__setattr__(self, "position", _nonneg("shaker position", self.position))
        for n in ("gauge_mass", "moving_mass", "suspension_stiffness"):
            object.__setattr__(self, n, _nonneg(f"shaker {n}", getattr(self, n)))
        object.__setattr__(
            self,
            "stinger_stiffness",
            _nonneg("shaker stinger_stiffness", self.stinger_stiffness, positive=True),
        )
        if self.force_at not in FORCE_AT:
            raise ValueError(f"force_at must be one of {FORCE_AT}, got {self.force_at!r}")
        if self.force_at != "gauge" and self.moving_mass <= 0:
            raise ValueError(
                f"moving_mass must be > 0 when the armature is in the model "
                f"(force_at={self.force_at!r}), got {self.moving_mass!r}"
            )

    @property
    def armature(self) -> bool:
        """True when the moving mass is a coordinate of the model."""
        return self.force_at != "gauge"


@dataclass(frozen=True)
class Clamp:
    """Springs holding the root of a clamped beam (beam A's end).

    Parameters
    ----------
    translational : float
        Axial and transverse stiffness [N/m], > 0.
    rotational : float
        Rotational stiffness about the width axis [N m/rad], > 0.
    """

    translational: float
    rotational: float

    def __post_init__(self):
        plain_fields(self)
        object.__setattr__(
            self, "translational", _nonneg("clamp translational", self.translational, positive=True)
        )
        object.__setattr__(
            self, "rotational", _nonneg("clamp rotational", self.rotational, positive=True)
        )


@dataclass(frozen=True)
class Setup:
    """What a test attaches to a specimen (module docstring).

    Parameters
    ----------
    name : str
        E.g. ``"hammer"``, ``"shaker"``.
    masses : tuple of PointMass
        Sensors and fixtures on the axis; names unique.
    shaker : Shaker or None
    clamp : Clamp or None
        ``None``: a clamped beam's root is rigid.
    ranges : tuple of (str, (float, float))
        Physical ranges of the setup's values for updating, by parameter name
        (``"mass:<name>"``, ``"shaker.gauge_mass"``, ``"clamp.rotational"``, ...); those not
        given take :func:`~iwan_element.models.updating.updatable`'s defaults.
    reference : str
        Where the values come from (a data sheet, a typical value).
    """

    name: str = "none"
    masses: tuple = ()
    shaker: Shaker | None = None
    clamp: Clamp | None = None
    ranges: tuple = field(default=())
    reference: str = ""

    def __post_init__(self):
        plain_fields(self)
        ms = tuple(self.masses)
        if not all(isinstance(m, PointMass) for m in ms):
            raise ValueError("masses must be a sequence of PointMass")
        names = [m.name for m in ms]
        if len(set(names)) != len(names):
            raise ValueError(f"masses must have distinct names, got {names}")
        object.__setattr__(self, "masses", ms)
        if self.shaker is not None and not isinstance(self.shaker, Shaker):
            raise ValueError(f"shaker must be a Shaker or None, got {type(self.shaker).__name__}")
        if self.clamp is not None and not isinstance(self.clamp, Clamp):
            raise ValueError(f"clamp must be a Clamp or None, got {type(self.clamp).__name__}")
        rg = dict(self.ranges)
        for k, r in rg.items():
            lo, hi = (float(v) for v in r)
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
                raise ValueError(
                    f"ranges[{k!r}] must be (low, high) with 0 <= low < high, got {r!r}"
                )
            rg[k] = (lo, hi)
        object.__setattr__(self, "ranges", tuple(sorted(rg.items())))

    @property
    def empty(self) -> bool:
        """Nothing attached and a rigid clamp (the nominal, bare specimen)."""
        return not self.masses and self.shaker is None and self.clamp is None

    def describe(self) -> str:
        """One line naming what is attached."""
        parts = [f"{m.name} {1e3 * m.mass:.3g} g at {m.position:.4g} m" for m in self.masses]
        if self.shaker is not None:
            sh = self.shaker
            parts.append(
                f"shaker at {sh.position:.4g} m (gauge {1e3 * sh.gauge_mass:.3g} g"
                + (
                    f", moving {1e3 * sh.moving_mass:.3g} g on a stinger of "
                    f"{sh.stinger_stiffness:.3g} N/m"
                    if sh.armature
                    else ""
                )
                + f", force at the {sh.force_at})"
            )
        if self.clamp is not None:
            parts.append(
                f"clamp {self.clamp.translational:.3g} N/m, {self.clamp.rotational:.3g} N m/rad"
            )
        return f"setup {self.name!r}: " + ("; ".join(parts) if parts else "nothing attached")
