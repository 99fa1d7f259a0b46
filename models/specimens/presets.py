"""Published lap-joint specimens and the test setups their tests used.

Presets (:func:`preset`; docs/equations.md section 7 for every published number):

``"example"``
    Today's example: two 200 x 40 x 10 mm steel beams, 50 mm lap, one M16 bolt at 30 kN in the
    lap centre, clamped-free (the seed paper's specimen size; synthetic).
``"brake-reuss"``
    The thin Brake-Reuss beam of Chen et al. (MSSP 166:108401, 2022) measured in
    ``shared/data/brb-hammer``: 720 mm long, 12.7 mm high, 25.4 mm wide, 120 mm lap with
    each half 6.35 mm thick in it, three 5/16 in bolts at the lap centre and +-30 mm,
    washers 17.46 mm OD; free-free; hammer and sensor (acc3) 76.2 mm from one end; first
    bending mode about 80.4 Hz; measured range 2-60 um at acc3. Material 304 stainless
    (nominal E = 192.31 GPa as in tmdsimpy's BRB model, updated to 194.52 GPa on the hammer
    record's low-amplitude bending frequencies with the stuck interface's stiffness,
    ``models.linear_update``; density 8000 kg/m^3 assumed). Bolt preload 12 kN (the classic
    BRB's measured mean is 12.25 kN; the thin BRB's torque is not verified). The interface
    parameters are the calibration of ``calibration.py`` on the measured ring-down after that
    update (``docs/linear_update.md``). Setups: ``"hammer"`` (three accelerometers) and
    ``"shaker"`` (the stepped sine's shaker and force gauge at acc3).
``"two-bolt-aluminium"``
    Two aluminium beams 270 x 25.4 x 6.35 mm (UNESP-BERT data set, shm-unesp/DATASET_BOLTEDBEAM),
    clamped-free, shaker 85 mm from the clamp, laser vibrometer at the free end. The data set
    states only the 5 N m torque; the lap length (50.8 mm), two M6 bolts at +-12.7 mm from the
    lap centre and the preload from the torque (Shigley's T = K F d, nut factor K = 0.2:
    F = 5 / (0.2 x 0.006) = 4.17 kN) are ASSUMPTIONS, stated here. Its setup (``"shaker"``)
    holds the shaker's moving mass on its stinger and suspension and a clamp that is not
    rigid, with field-typical values and ranges (``PRESET_SETUPS``), not verified.
"""

from __future__ import annotations

from .setups import Clamp, PointMass, Setup, Shaker
from .specimen import Excitation, InterfaceModel, Specimen

__all__ = ["preset", "PRESETS", "PRESET_SETUPS"]


def _example() -> Specimen:
    return Specimen(
        name="example",
        beam_length=0.2,
        width=0.04,
        thickness=0.01,
        lap_thickness=0.01,
        youngs_modulus=2.1e11,
        density=7850.0,
        overlap=0.05,
        bolt_positions=(0.025,),
        preload=30.0e3,
        bolt_diameter=0.016,
        washer_diameter=0.030,
        friction=0.3,
        boundary="clamped-free",
        excitation=Excitation("hammer", 0.35),
        sensor_position=0.35,
        amplitude_range=(1e-6, 3e-4),
        interface=InterfaceModel(
            n_points=24, stiffness_per_area=2.0e12, chi=-0.5, beta=0.1, damping_floor=5e-4
        ),
        n_elements=16,
        reference="the project's example: seed paper specimen size (M16 10.9, 30 kN), synthetic",
    )


def _brake_reuss() -> Specimen:
    # The route of benchmarks/bench_linear_update.py on the thin BRB hammer record
    # (brb-hammer/, the shared data, read in place), on the hammer setup: Young's modulus
    # (nominal 192.31 GPa) and the stiffness per area updated on the low-amplitude first and
    # second bending frequencies (models.linear_update), then the interface calibrated on
    # mode 1's amplitude curve at acc3 (calibration.py).
    return Specimen(
        name="brake-reuss",
        beam_length=0.42,
        width=0.0254,
        thickness=0.0127,
        lap_thickness=0.00635,
        youngs_modulus=194.52e9,
        density=8000.0,
        overlap=0.12,
        bolt_positions=(0.03, 0.06, 0.09),
        preload=12.0e3,
        bolt_diameter=0.0079375,
        washer_diameter=0.01746,
        friction=0.4300,
        boundary="free-free",
        excitation=Excitation("hammer", 0.72 - 0.0762),
        sensor_position=0.72 - 0.0762,
        amplitude_range=(2e-6, 60e-6),
        calibrated_range=(2e-6, 60e-6),
        interface=InterfaceModel(
            n_points=40, stiffness_per_area=8.060e11, chi=-0.4954, beta=0.1, damping_floor=1.2821e-3
        ),
        n_elements=20,
        reference="thin BRB, Chen et al. MSSP 166:108401 (2022); classic BRB bolts/washers "
        "(Balaji, Abaqus4Joints); nominal E 192.31 GPa from Porter & Brake MSSP "
        "192:110210 (2023), updated to 194.52 GPa on the hammer record's "
        "low-amplitude bending frequencies (benchmarks/bench_linear_update.py)",
    )


def _two_bolt_aluminium() -> Specimen:
    return Specimen(
        name="two-bolt-aluminium",
        beam_length=0.27,
        width=0.0254,
        thickness=0.00635,
        lap_thickness=0.00635,
        youngs_modulus=70.0e9,
        density=2700.0,
        overlap=0.0508,
        bolt_positions=(0.0127, 0.0381),
        preload=4.17e3,
        bolt_diameter=0.006,
        washer_diameter=0.012,
        friction=0.5,
        boundary="clamped-free",
        excitation=Excitation("shaker", 0.085),
        sensor_position=2 * 0.27 - 0.0508,
        amplitude_range=(5e-6, 5e-4),
        interface=InterfaceModel(
            n_points=32, stiffness_per_area=1.0e12, chi=-0.5, beta=0.1, damping_floor=1e-3
        ),
        n_elements=16,
        reference="UNESP-BERT (shm-unesp/DATASET_BOLTEDBEAM): beams, cantilever, shaker at 85 mm; "
        "lap 50.8 mm, two M6 bolts, preload from 5 N m with K = 0.2: assumed",
    )


PRESETS = {
    "example": _example,
    "brake-reuss": _brake_reuss,
    "two-bolt-aluminium": _two_bolt_aluminium,
}

_BRB_SENSORS = (("acc1", 0.0254), ("acc2", 0.5549), ("acc3", 0.72 - 0.0762))
_BRB_SENSOR_REF = (
    "three accelerometers at the data README's positions; their masses are not "
    "stated in the source: 3 g each (a miniature ICP accelerometer's), range "
    "0.5-12 g"
)


def _brb_setups() -> dict:
    sensors = tuple(PointMass(n, x, 0.003) for n, x in _BRB_SENSORS)
    ranges = tuple((f"mass:{n}", (0.0005, 0.012)) for n, _ in _BRB_SENSORS)
    return {
        "hammer": Setup(
            name="hammer",
            masses=sensors,
            ranges=ranges,
            reference="hammer test, free-free: " + _BRB_SENSOR_REF,
        ),
        "shaker": Setup(
            name="shaker",
            masses=sensors,
            shaker=Shaker(
                0.72 - 0.0762,
                gauge_mass=0.005,
                moving_mass=0.15,
                stinger_stiffness=1.0e6,
                force_at="gauge",
            ),
            ranges=ranges
            + (("shaker.gauge_mass", (0.0005, 0.03)), ("shaker.moving_mass", (0.03, 0.6))),
            reference="force-controlled stepped sine: a shaker at acc3 with a force gauge "
            "(mass below its sensing element 5 g, range 0.5-30 g: typical of an "
            "ICP force gauge and its mounting stud; not stated in the source), its stinger "
            "attached at the drawing's 76.2 mm from the end (range +-5 mm: half a force "
            "gauge's 12-17 mm mounting base and the hand placement of a stinger; the drive "
            "point moves with it, acc3 on the other face stays) and the moving parts behind "
            "the gauge (not seen by a force-measured test); " + _BRB_SENSOR_REF,
        ),
    }


def _two_bolt_setups() -> dict:
    return {
        "shaker": Setup(
            name="shaker",
            shaker=Shaker(
                0.085,
                gauge_mass=0.002,
                moving_mass=0.1,
                stinger_stiffness=1.0e6,
                suspension_stiffness=5.0e3,
                force_at="armature",
            ),
            clamp=Clamp(translational=1.0e8, rotational=3.0e3),
            ranges=(
                ("shaker.gauge_mass", (0.0, 0.01)),
                ("shaker.moving_mass", (0.02, 0.3)),
                ("shaker.stinger_stiffness", (1.0e5, 1.0e7)),
                ("shaker.suspension_stiffness", (1.0e3, 2.0e4)),
                ("clamp.translational", (1.0e6, 1.0e10)),
                ("clamp.rotational", (3.0e2, 3.0e4)),
            ),
            reference="the data set's description (UNESP-BERT): a Modal Shop 2400E shaker 85 mm "
            "from the clamp, driven by its amplifier (no force gauge stated: the force "
            "acts on the moving mass), a laser vibrometer (no mass) at the free end, a "
            "bench clamp. Field-typical values, NOT verified for this rig: moving mass "
            "0.1 kg (0.02-0.3), stinger 1e6 N/m (1e5-1e7), suspension 5e3 N/m "
            "(1e3-2e4), stinger fixture 2 g (0-10); clamp 1e8 N/m (1e6-1e10) and "
            "3e3 N m/rad (3e2-3e4; the beam's own EI/L is 77 N m/rad)",
        )
    }


#: The setups each preset's tests used, the first its default (:func:`preset`).
PRESET_SETUPS = {
    "example": lambda: {"none": Setup()},
    "brake-reuss": _brb_setups,
    "two-bolt-aluminium": _two_bolt_setups,
}


def preset(name: str, *, setup: str | Setup | None = None) -> Specimen:
    """The specimen description of a named preset (see the module docstring) on one of its
    test setups.

    Parameters
    ----------
    name : {"example", "brake-reuss", "two-bolt-aluminium"}
    setup : str or Setup, optional, keyword-only
        A setup the preset declares (:data:`PRESET_SETUPS`: ``"brake-reuss"`` has
        ``"hammer"`` (default) and ``"shaker"``; ``"two-bolt-aluminium"`` ``"shaker"``;
        ``"example"`` ``"none"``), or a :class:`~iwan_element.models.specimens.setups.Setup`.

    Returns
    -------
    Specimen
        Frozen; ``specimen.replace(...)`` or ``dataclasses.replace`` makes variants.
    """
    if not isinstance(name, str) or name not in PRESETS:
        raise ValueError(f"name must be one of {sorted(PRESETS)}, got {name!r}")
    spec = PRESETS[name]()
    setups = PRESET_SETUPS[name]()
    if setup is None:
        setup = next(iter(setups.values()))
    elif isinstance(setup, str):
        if setup not in setups:
            raise ValueError(
                f"setup must be one of {sorted(setups)} for {name!r} or a Setup, got {setup!r}"
            )
        setup = setups[setup]
    elif not isinstance(setup, Setup):
        raise ValueError(f"setup must be a setup name or a Setup, got {type(setup).__name__}")
    return spec.replace(setup=setup)
