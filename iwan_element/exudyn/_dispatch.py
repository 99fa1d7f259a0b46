"""The post-step dispatcher shared by all Iwan connectors and interfaces of one system,
the settings they refuse, and the ownership of joint elements."""
from __future__ import annotations

import math
import weakref

import exudyn as exu

__all__: list[str] = []

_NAN = math.nan

# ---------------------------------------------------------------------------- dispatcher
def _installed_post_step(mbs):
    """The Python object currently set as post-step user function, or ``None``.

    Exudyn 1.13.6 returns ``0`` when none is set and a dict ``{'function': f, 'type': ...}``
    otherwise (older versions returned ``f`` itself); both forms are accepted.
    """
    got = mbs.GetPostStepUserFunction()
    if isinstance(got, dict):
        got = got.get("function", 0)
    if got is None or (isinstance(got, int) and got == 0):
        return None
    return got


class _PostStepDispatcher:
    """Commits every connector of one system once per accepted step, then calls the
    previously installed post-step function (``chained``)."""

    def __init__(self, chained, mbs):
        self.chained = chained
        self.connectors = []       # in creation order
        self.last_t = _NAN
        self.running = False
        self.solvers = (None, None)    # the solver objects of the run the views belong to
        conns = self.connectors
        disp = self
        self.sysd = mbs.sys        # Exudyn's SolveDynamic/SolveStatic store their solver here

        def post_step_dispatcher(mbs, t):
            if disp.running:       # re-entered through a user function that calls us by hand
                return True
            disp.running = True
            try:
                sysd = disp.sysd
                solvers = (sysd.get("dynamicSolver"), sysd.get("staticSolver"))
                if solvers[0] is not disp.solvers[0] or solvers[1] is not disp.solvers[1]:
                    disp.solvers = solvers     # a new solve (maybe after an Assemble)
                    disp.new_solve(mbs)
                if t > disp.last_t:            # the usual case: the next accepted step
                    disp.last_t = t
                    for c in conns:
                        c._accept(t)
                elif t != disp.last_t:         # a new run (never commit twice at one time)
                    disp.last_t = t
                    disp.refresh(mbs)
                    for c in conns:
                        c._accept(t)
                else:                          # a run continuing from the last accepted time
                    disp.refresh(mbs)
                f = disp.chained
                return True if f is None else f(mbs, t)
            finally:
                disp.running = False

        post_step_dispatcher._iwan_dispatcher = self
        self.callback = post_step_dispatcher

    def add(self, connector: "IwanConnector") -> None:
        self.connectors.append(connector)

    def refresh(self, mbs) -> None:
        """Let every connector take fresh views of the system coordinates.

        Exudyn keeps its coordinate vectors in place during a run and across runs; only an
        ``Assemble`` that makes them longer moves them (exudyn 1.13.6). So the views are
        renewed at the start of every run: a new solver object in ``mbs.sys`` (each
        ``SolveDynamic``/``SolveStatic`` stores one), or an accepted time not after the last.
        """
        for c in self.connectors:
            c._refresh(mbs)

    def new_solve(self, mbs) -> None:
        """Start of a solve: refuse settings the connectors cannot serve, then refresh."""
        settings = mbs.sys.get("simulationSettings")
        if settings is not None:
            check_settings(settings, self.connectors)
        self.refresh(mbs)

    @staticmethod
    def of(obj):
        """The dispatcher whose callback ``obj`` is, else ``None``."""
        return getattr(obj, "_iwan_dispatcher", None)

    def reachable_from(self, fn) -> bool:
        """True if this dispatcher runs when ``fn`` is the installed post-step function."""
        seen = 0
        while fn is not None and seen < 1000:
            d = _PostStepDispatcher.of(fn)
            if d is None:
                return False
            if d is self:
                return True
            fn = d.chained
            seen += 1
        return False

    def rebind(self, sysd) -> None:
        """Read the solver objects from ``sysd`` (the hook that replaced ``mbs.sys``)."""
        self.sysd = sysd

    def install(self, mbs) -> None:
        """Put this dispatcher in front of whatever post-step function is installed now."""
        current = _installed_post_step(mbs)
        if current is self.callback:
            return
        self.chained = current
        mbs.SetPostStepUserFunction(self.callback)


def check_settings(settings, connectors) -> None:
    """Refuse, before the first step, solver settings the joints cannot serve exactly.

    * more than one solver thread with a Python force law: with two threads Exudyn 1.13.6
      was seen to hang with about 20 or more Python-function connectors (the symbolic law
      runs without Python and is allowed);
    * an explicit solver with automatic step size (ODE23, DOPRI5): the joint's history is
      committed once per accepted step, so a reversal inside a step is not seen by the
      solver's error estimate; measured on the 1-DOF free-decay model (tests), DOPRI5 at
      tolerances 1e-6, 1e-8 and 1e-10 missed the converged implicit result by 7e-3, 1e-4 and
      8e-3 of the amplitude. Fixed-step explicit methods converge as the step falls and are
      allowed; pass ``allow_adaptive_explicit=True`` to the connector to run anyway.
    """
    python = [c for c in connectors if getattr(c, "_route", "python") == "python"]
    threads = settings.parallel.numberOfThreads
    if python and threads > 1:
        raise ValueError(
            f"simulationSettings.parallel.numberOfThreads = {threads}: {len(python)} Iwan "
            "connector(s) use a Python force law, which is not safe with several solver "
            "threads (Exudyn was seen to hang); set numberOfThreads = 1, or use IwanJoint "
            "elements (symbolic law, law='auto') or add_iwan_interface")
    ti = settings.timeIntegration
    if ti.solverType in ADAPTIVE_EXPLICIT and ti.automaticStepSize:
        strict = [c for c in connectors if not getattr(c, "_allow_adaptive_explicit", False)]
        if strict:
            raise ValueError(
                f"solverType {ti.solverType} with automaticStepSize = True is refused for Iwan "
                "joints: a reversal inside a step is invisible to its error estimate, and the "
                "result does not converge with the tolerance (errors of 1e-4 to 1e-2 of the "
                "amplitude were measured); use GeneralizedAlpha, or a fixed step "
                "(automaticStepSize = False), or pass allow_adaptive_explicit=True")


ADAPTIVE_EXPLICIT = frozenset({exu.DynamicSolverType.ODE23, exu.DynamicSolverType.DOPRI5})


class _SolveHook(dict):
    """Replaces ``mbs.sys`` (same content): ``SolveDynamic``/``SolveStatic`` store their solver
    in it before the first step, which puts every dispatcher of the system back in front of
    a post-step function set after the connectors (it is then chained, not lost)."""

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        if key in ("dynamicSolver", "staticSolver"):
            mbs = self.mbs
            for d in self.dispatchers:
                if not d.reachable_from(_installed_post_step(mbs)):
                    d.install(mbs)


def _dispatcher_for(mbs) -> _PostStepDispatcher:
    current = _installed_post_step(mbs)
    d = _PostStepDispatcher.of(current)
    if d is not None:
        return d
    d = _PostStepDispatcher(current, mbs)
    mbs.SetPostStepUserFunction(d.callback)
    hook = mbs.sys
    if not isinstance(hook, _SolveHook):
        hook = _SolveHook(hook)
        hook.mbs = mbs
        hook.dispatchers = []
        mbs.sys = hook
        d.rebind(hook)
    hook.dispatchers.append(d)
    return d


# ---------------------------------------------------------------------------- ownership
_ATTACHED: dict = {}        # id(element) -> (weakref to its connector, the element)


def _claim(joint, handle) -> None:
    """Refuse an element that a live connector (of any system) already uses: its history
    would be shared by two force laws."""
    key = id(joint)
    got = _ATTACHED.get(key)
    if got is not None and got[1] is joint:
        owner = got[0]()
        if owner is not None:
            raise ValueError(
                f"joint is already attached to {owner!r} (possibly in another system); its "
                "history would be shared: give every connector its own element instance")
    _ATTACHED[key] = (weakref.ref(handle), joint)
    for k in [k for k, (ref, _) in _ATTACHED.items() if ref() is None]:
        del _ATTACHED[k]
