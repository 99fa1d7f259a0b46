"""The post-step dispatcher shared by all Iwan connectors and interfaces of one system,
the settings they refuse, and the ownership of joint elements.
"""

from __future__ import annotations

import logging
import math
import weakref
from typing import TYPE_CHECKING, Any

import exudyn as exu

if TYPE_CHECKING:
    from ._connector_handle import IwanConnector
    from .interface_handle import IwanInterface

__all__: list[str] = []

_log = logging.getLogger("iwan_element.exudyn.connector")
_NAN = math.nan


# ---------------------------------------------------------------------------- dispatcher
def _installed_post_step(mbs):
    """The Python object currently set as post-step user function, or ``None``."""
    return _installed(mbs.GetPostStepUserFunction())


def _installed(got):
    """A user function as Exudyn's getters return it, or ``None``.

    Exudyn 1.13.6 returns ``0`` when none is set and a dict ``{'function': f, 'type': ...}``
    otherwise (older versions returned ``f`` itself); both forms are accepted.
    """
    if isinstance(got, dict):
        got = got.get("function", 0)
    if got is None or (isinstance(got, int) and got == 0):
        return None
    return got


class _PostStepDispatcher:
    """Commits every connector of one system once per accepted step, then calls the
    previously installed post-step function (``chained``).

    The per-step path is one comparison of times, a flag and the connectors' accept
    functions; a new solve is announced by the ``mbs.sys`` hook (:class:`_SolveHook`) or
    recognised by an accepted time not after the last one.
    """

    def __init__(self, chained, mbs):
        self.chained = chained
        self.connectors = []  # in creation order
        self.accepts = ()  # their accept functions, renewed with the views
        self.solo = None  # the accept function if there is exactly one
        self.last_t = _NAN
        self.running = False
        self.stale = True  # a new solve was announced: check settings, renew views
        self.solvers = (None, None)  # the solver objects of the run the views belong to
        self.risky = []  # connectors whose stack is deeper than their law holds
        self.pn_prev = None  # post-Newton function found when ours was installed
        self.pn_big = 1e10  # "discontinuous error" that asks for a re-solve
        self.recorders = []  # energy recorders of this system (follow resets)
        self.solve_info = None  # (kind, solver type, spectral radius) of the last solve
        self.mbs = mbs
        disp = self
        self.sysd = mbs.sys  # Exudyn's SolveDynamic/SolveStatic store their solver here

        def post_step_dispatcher(mbs, t):
            if t > disp.last_t and not disp.stale and not disp.running:
                disp.last_t = t  # the usual case: the next accepted step of this run
                solo = disp.solo
                if solo is not None:
                    solo(t)
                else:
                    for a in disp.accepts:
                        a(t)
                f = disp.chained
                if f is None:
                    return True
            else:
                if disp.running:  # re-entered through a user function that calls us by hand
                    return True
                disp.slow_step(mbs, t)
                f = disp.chained
                if f is None:
                    return True
            disp.running = True
            try:
                return f(mbs, t)
            finally:
                disp.running = False

        def post_newton(mbs, t):
            err = 0.0
            for c in disp.risky:
                err = max(err, c._newton_check(disp.pn_big))
            f = disp.pn_prev
            if f is None:
                return [err, -1.0]
            got = f(mbs, t)
            return [max(err, float(got[0])), float(got[1])]

        post_step_dispatcher._iwan_dispatcher = self
        post_newton._iwan_dispatcher = self
        self.callback = post_step_dispatcher
        self.post_newton = post_newton

    def slow_step(self, mbs, t) -> None:
        """A step that is not the plain next one: a new solve, a new run, a continued run."""
        sysd = self.sysd
        solvers = (sysd.get("dynamicSolver"), sysd.get("staticSolver"))
        if self.stale or solvers[0] is not self.solvers[0] or solvers[1] is not self.solvers[1]:
            self.solvers = solvers  # a new solve (maybe after an Assemble)
            self.stale = False
            self.new_solve(mbs)
            self.last_t = t
            for a in self.accepts:
                a(t)
        elif t > self.last_t:
            self.last_t = t
            for a in self.accepts:
                a(t)
        elif t != self.last_t:  # a new run (never commit twice at one time)
            # not announced by the mbs.sys hook (storeSolver=False): a fresh history from
            # here; the solver's initial accelerations still saw the old one
            for c in self.connectors:
                c.reset()
            _log.warning(
                "a run starts at t=%g, before the last accepted time, without "
                "SolveDynamic's storeSolver=True: the Iwan joints start a fresh "
                "history at its first step (its initial accelerations used the old "
                "one; keep storeSolver=True)",
                t,
            )
            self.last_t = t
            self.refresh(mbs)
            for a in self.accepts:
                a(t)
        else:  # a run continuing from the last accepted time
            self.refresh(mbs)

    def lazy_until(self) -> float:
        """Accepted steps before this time may commit joints lazily: the last step of the
        dynamic run being solved, known only if the ``mbs.sys`` hook saw it start and no
        other post-step function (which might read the joints) is chained (the energy
        recorders, called among the accept functions, read none); else never.
        """
        sysd = self.sysd
        if self.chained is not None or getattr(sysd, "kind", None) != "dynamicSolver":
            return -math.inf
        settings = sysd.get("simulationSettings")
        if settings is None:
            return -math.inf
        ti = settings.timeIntegration
        h = (ti.endTime - ti.startTime) / max(1, ti.numberOfSteps)
        return ti.endTime - 0.5 * abs(h)

    def set_risky(self, connector, risky: bool) -> None:
        """Install the post-Newton check while some connector's committed stack is deeper
        than its law holds (only then can a step need points the law does not hold).
        """
        if risky and connector not in self.risky:
            self.risky.append(connector)
        elif not risky and connector in self.risky:
            self.risky.remove(connector)
        mbs = self.mbs
        current = _installed(mbs.GetPostNewtonUserFunction())
        if self.risky and current is not self.post_newton:
            self.pn_prev = current
            mbs.SetPostNewtonUserFunction(self.post_newton)
        elif not self.risky and current is self.post_newton:
            mbs.SetPostNewtonUserFunction(0 if self.pn_prev is None else self.pn_prev)
            self.pn_prev = None

    def add(self, connector: IwanConnector | IwanInterface) -> None:
        self.connectors.append(connector)
        self.stale = True

    def refresh(self, mbs) -> None:
        """Let every connector take fresh views of the system coordinates.

        Exudyn keeps its coordinate vectors in place during a run and across runs; only an
        ``Assemble`` that makes them longer moves them (exudyn 1.13.6). So the views are
        renewed at the start of every run: a new solver object in ``mbs.sys`` (each
        ``SolveDynamic``/``SolveStatic`` stores one), or an accepted time not after the last.
        """
        lazy = self.lazy_until()
        for c in self.connectors:
            if getattr(c, "_lazy", False):
                c._refresh(mbs, lazy)
            else:
                c._refresh(mbs)
        for r in self.recorders:
            r._refresh(mbs)
        self.accepts = tuple(c._accept for c in self.connectors) + tuple(
            r._record for r in self.recorders
        )  # after the joints
        self.solo = self.accepts[0] if len(self.accepts) == 1 else None

    def before_solve(self, settings, kind: str) -> None:
        """A solve is about to start (announced by the ``mbs.sys`` hook, before Exudyn's
        solver runs): refuse settings the joints cannot serve, and give every joint a fresh
        history if the solve starts before the last accepted time (a new run, not a
        continuation): the joints return to their virgin state, their records and the energy
        recorders of this system start again (an initial slip is then reached by monotone
        virgin loading, as in the first run).
        """
        check_settings(settings, self.connectors)
        ti = settings.timeIntegration
        self.solve_info = (kind, ti.solverType, ti.generalizedAlpha.spectralRadius)
        t0 = (
            settings.timeIntegration.startTime
            if kind == "dynamicSolver"
            else settings.staticSolver.loadStepStart
        )
        last = self.last_t
        if last == last and t0 < last - 1e-12 * max(1.0, abs(last)):
            for c in self.connectors:
                c.reset()
            _log.info(
                "a solve starts at t=%g, before the last accepted time t=%g: %d Iwan "
                "joint(s) start a fresh history",
                t0,
                last,
                len(self.connectors),
            )
        self.last_t = _NAN

    def add_recorder(self, recorder) -> None:
        """An energy recorder, called after the joints at every accepted step (not chained:
        a post-step function set later by the user does not drop it).
        """
        self.recorders.append(recorder)
        self.stale = True

    def joint_reset(self, joint) -> None:
        """A joint of this system was reset: the energy recorders holding it start again."""
        for r in self.recorders:
            r._joint_reset(joint)

    def new_solve(self, mbs) -> None:
        """Start of a solve: refuse settings the connectors cannot serve, then refresh."""
        settings = self.sysd.get("simulationSettings")
        if settings is not None:
            check_settings(settings, self.connectors)
            tol = settings.timeIntegration.discontinuous.iterationTolerance
            self.pn_big = max(1e10, 1e3 * abs(tol))
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
            "elements (symbolic law, law='auto') or add_iwan_interface"
        )
    ti = settings.timeIntegration
    if ti.solverType in ADAPTIVE_EXPLICIT and ti.automaticStepSize:
        strict = [c for c in connectors if not getattr(c, "_allow_adaptive_explicit", False)]
        if strict:
            raise ValueError(
                f"solverType {ti.solverType} with automaticStepSize = True is refused for Iwan "
                "joints: a reversal inside a step is invisible to its error estimate, and the "
                "result does not converge with the tolerance (errors of 1e-4 to 1e-2 of the "
                "amplitude were measured); use GeneralizedAlpha, or a fixed step "
                "(automaticStepSize = False), or pass allow_adaptive_explicit=True"
            )


ADAPTIVE_EXPLICIT = frozenset({exu.DynamicSolverType.ODE23, exu.DynamicSolverType.DOPRI5})


class _SolveHook(dict):
    """Replaces ``mbs.sys`` (same content): ``SolveDynamic``/``SolveStatic`` store their solver
    and then their settings in it before the first step (exudyn 1.13.6, ``storeSolver=True``,
    the default). The solver puts every dispatcher of the system back in front of a
    post-step function set after the connectors (it is then chained, not lost); the settings
    let each dispatcher refuse what its joints cannot serve and start a fresh history
    (:meth:`_PostStepDispatcher.before_solve`) - a ``ValueError`` raised here leaves
    ``SolveDynamic`` before the solver starts.
    """

    # set on the instance by _dispatcher_for (annotations only: a dict subclass's attributes)
    mbs: Any  # the exudyn MainSystem
    dispatchers: list[_PostStepDispatcher]
    kind: str
    pending: bool

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        if key in ("dynamicSolver", "staticSolver"):
            self.kind = key  # the solve about to start
            self.pending = True
            mbs = self.mbs
            for d in self.dispatchers:
                d.stale = True
                if not d.reachable_from(_installed_post_step(mbs)):
                    d.install(mbs)
        elif key == "simulationSettings" and getattr(self, "pending", False):
            self.pending = False
            for d in self.dispatchers:
                d.before_solve(value, self.kind)


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
_ATTACHED: dict = {}  # id(element) -> (weakref to its connector, the element)


def _claim(joint, handle) -> None:
    """Refuse an element that a live connector (of any system) already uses: its history
    would be shared by two force laws.
    """
    key = id(joint)
    got = _ATTACHED.get(key)
    if got is not None and got[1] is joint:
        owner = got[0]()
        if owner is not None:
            raise ValueError(
                f"joint is already attached to {owner!r} (possibly in another system); its "
                "history would be shared: give every connector its own element instance"
            )
    _ATTACHED[key] = (weakref.ref(handle), joint)
    for k in [k for k, (ref, _) in _ATTACHED.items() if ref() is None]:
        del _ATTACHED[k]
