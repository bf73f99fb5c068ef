"""The extended Oxley predictive machining model with Johnson-Cook flow stress (orthogonal cutting).

Oxley's parallel-sided shear zone theory (P. L. B. Oxley, *Mechanics of Machining*, Ellis Horwood 1989)
with the Johnson-Cook flow stress and temperature-dependent thermal properties, as extended by
D. A. Lalwani, N. K. Mehta, P. K. Jain, J. Mater. Process. Technol. 209 (2009) 5305-5312. Written here
from the published equations; units SI (m, s, Pa, N, K), angles in radians.

Unknowns and the conditions that fix them (one pass of :func:`predict`):

* shear angle ``phi``: the shear stress on the tool-chip interface from the forces, ``tau_int = F / (h w)``,
  equals the chip's flow shear stress there, ``k_int`` (Johnson-Cook at the interface's strain, strain
  rate and temperature) -- Brent's root in a bracket stepped out from the last root, or scanned down from
  ``phi_max`` (the largest root, where ``tau_int - k_int`` goes from + to -: a smaller root where the shear
  plane melts is spurious);
* strain-rate constant ``C0`` (shear plane length over primary zone thickness): the normal stress on the
  interface from the forces, ``N / (h w)``, equals the one at the tool tip from the stress field,
  ``k_AB (1 + pi/2 - 2 alpha - 2 C0 n_eq)`` -- Brent's root (bracket from the last root, else a 9-point
  scan of ``C0_range``), not a grid;
* ``delta`` (secondary zone thickness over chip thickness): the cutting force is a minimum
  (Oxley's minimum-work hypothesis) -- a 7-point scan of ``delta_range``, then bounded Brent minimisation.

Where a condition has no root in its range (low speeds, tiny h, large rakes) :class:`OxleyError` says so;
a state where the resultant leaves the shear plane's range is a NaN residual that the searches step over.

Inner fixed points (safeguarded secant, to 1e-12, warm-started): the shear-plane temperature ``T_AB`` (its
flow stress sets the heat it makes), and, with ``properties = "chip"`` or ``"interface"``, the temperature at
which the chip's conductivity and heat capacity are taken in the secondary zone (:data:`PROPERTY_TEMPERATURES`).

Heat: Boothroyd's partition into the workpiece ``beta`` (0.5 - 0.35 lg(R_T tan phi), or 0.3 - 0.15 lg(...)
above 10), ``T_AB = T_w + eta dT_sz``; Oxley's chip-tool interface rise
``lg(dT_M / dT_c) = 0.06 - 0.195 delta sqrt(R_T t2 / h) + 0.5 lg(R_T t2 / h)``, ``T_int = T_w + dT_sz + psi dT_M``.

The module is longer than 300 lines on purpose: the equations, their fixed points and the root searches
are one published algorithm, read together.

>>> r = predict(AISI1045_LALWANI, AISI1045_LALWANI_THERMAL, Cut(speed=200 / 60, uncut=0.15e-3,
...             width=1.6e-3, rake=math.radians(-7), T_work=298.15))
>>> round(r.Fc), round(r.Ft), round(r.chip_thickness * 1e3, 2), round(r.T_int - 273.15)
(575, 352, 0.42, 955)
>>> round(math.degrees(merchant(r.friction_angle, r.rake)), 1), round(math.degrees(lee_shaffer(r.friction_angle, r.rake)), 1)
(29.3, 13.5)
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Callable

from scipy.optimize import brentq, minimize_scalar

SQRT3 = math.sqrt(3.0)


class OxleyError(ValueError):
    """The model has no solution for these inputs inside the search ranges (the message says which)."""


@dataclasses.dataclass(frozen=True)
class JohnsonCook:
    """Johnson-Cook flow stress ``(A + B eps^n)(1 + C ln(rate / rate0))(1 - T*^m)``, ``T* = (T - T_room) /
    (T_melt - T_room)`` clipped to [0, 1]; the rate term is not allowed below 1 (rates under rate0)."""

    A: float            # Pa
    B: float            # Pa
    n: float            # 1
    C: float            # 1
    m: float            # 1
    T_melt: float       # K
    T_room: float       # K
    rate0: float = 1.0  # 1/s

    def flow_stress(self, eps: float, rate: float, T: float) -> float:
        """Von Mises flow stress [Pa] at equivalent plastic strain ``eps``, rate ``rate`` [1/s], ``T`` [K]."""
        ts = min(max((T - self.T_room) / (self.T_melt - self.T_room), 0.0), 1.0)
        return ((self.A + self.B * eps ** self.n) * max(1.0 + self.C * math.log(rate / self.rate0), 1.0)
                * (1.0 - ts ** self.m))

    def n_eq(self, eps: float) -> float:
        """Equivalent strain-hardening index ``d ln(sigma) / d ln(eps)`` of the strain term (Lalwani et al.)."""
        return self.n * self.B * eps ** self.n / (self.A + self.B * eps ** self.n)


@dataclasses.dataclass(frozen=True)
class ThermalProperties:
    """Density, and conductivity and specific heat linear in temperature: ``k = k0 + k_slope (T - T0)``."""

    rho: float             # kg/m^3
    k0: float              # W/m/K at T0
    c0: float              # J/kg/K at T0
    T0: float = 273.15     # K
    k_slope: float = 0.0   # W/m/K^2
    c_slope: float = 0.0   # J/kg/K^2

    def k(self, T: float) -> float:
        return self.k0 + self.k_slope * (T - self.T0)

    def c(self, T: float) -> float:
        return self.c0 + self.c_slope * (T - self.T0)

    def thermal_number(self, T: float, speed: float, uncut: float) -> float:
        """``R_T = rho c V t1 / k`` at temperature ``T``."""
        k = self.k(T)
        if k <= 0 or self.c(T) <= 0:
            raise OxleyError(f"thermal properties not positive at {T - 273.15:.0f} C (k = {k:g} W/m/K, "
                             f"c = {self.c(T):g} J/kg/K): check their temperature slopes")
        return self.rho * self.c(T) * speed * uncut / k


@dataclasses.dataclass(frozen=True)
class Cut:
    """Orthogonal cutting conditions: speed [m/s], uncut chip thickness t1 [m], width w [m], rake [rad],
    workpiece temperature [K]."""

    speed: float
    uncut: float
    width: float
    rake: float
    T_work: float = 293.15


PROPERTY_TEMPERATURES: dict[str, Callable[[float, float, float], float]] = {
    "shear-plane": lambda T_AB, T_chip, T_int: T_AB,
    "chip": lambda T_AB, T_chip, T_int: T_chip,
    "interface": lambda T_AB, T_chip, T_int: T_int,
}
"""Where the chip's k and c are taken in the secondary zone (the primary zone always uses T_AB):
at the shear plane, at the chip's mean temperature ``T_w + dT_sz + dT_c`` (default), or at the interface."""


@dataclasses.dataclass(frozen=True)
class Options:
    """Model constants and search ranges (Oxley 1989; Lalwani et al. 2009)."""

    eta: float = 0.9                      # T_AB = T_w + eta dT_sz
    psi: float = 0.9                      # T_int = T_w + dT_sz + psi dT_M
    properties: str = "chip"              # key of PROPERTY_TEMPERATURES
    phi_range: tuple[float, float] = (math.radians(5.0), math.radians(45.0))
    C0_range: tuple[float, float] = (2.0, 10.0)
    delta_range: tuple[float, float] = (0.005, 0.2)

    def __post_init__(self):
        if self.properties not in PROPERTY_TEMPERATURES:
            raise OxleyError(f"unknown property temperature {self.properties!r}; "
                             f"valid: {', '.join(PROPERTY_TEMPERATURES)}")


@dataclasses.dataclass
class Result:
    """One Oxley prediction (SI units; angles in rad; temperatures in K)."""

    Fc: float                 # cutting force [N]
    Ft: float                 # thrust force [N]
    chip_thickness: float     # t2 [m]
    phi: float                # shear angle
    friction_angle: float     # lambda, tan(lambda) = F / N on the rake face
    theta: float              # angle between the resultant and the shear plane
    C0: float                 # shear plane length / primary zone thickness
    delta: float              # secondary zone thickness / chip thickness
    contact_length: float     # tool-chip contact length h [m]
    T_AB: float               # shear plane temperature [K]
    T_int: float              # mean tool-chip interface temperature [K]
    T_chip: float             # mean chip temperature [K]
    k_AB: float               # shear flow stress on the shear plane [Pa]
    k_int: float              # chip shear flow stress at the interface [Pa]
    sigma_N: float            # mean normal stress on the rake face [Pa]
    strain_AB: float          # equivalent plastic strain at AB
    rate_AB: float            # equivalent strain rate at AB [1/s]
    strain_int: float         # equivalent plastic strain at the interface
    rate_int: float           # equivalent strain rate at the interface [1/s]
    beta: float               # share of the primary zone's heat into the workpiece
    Fs: float                 # shear force on AB [N]
    F: float                  # friction force on the rake face [N]
    N: float                  # normal force on the rake face [N]
    rake: float
    uncut: float
    width: float
    inertia: float = 0.0      # rho V_s^2 / k_AB: momentum flux through the shear plane over its flow stress
    kinetic: float = 0.0      # chip kinetic energy flux over the cutting power, rho V_c^2 b t1 / (2 F_c)
    evaluations: int = 0      # model evaluations of the solve
    seconds: float = 0.0      # wall time of the solve

    @property
    def chip_ratio(self) -> float:
        """Chip compression ratio t2 / t1."""
        return self.chip_thickness / self.uncut

    @property
    def friction_coefficient(self) -> float:
        return math.tan(self.friction_angle)

    def as_dict(self) -> dict:
        """Plain numbers in SI plus the derived chip ratio, friction coefficient and classic shear angles."""
        d = dataclasses.asdict(self)
        d.update(chip_ratio=self.chip_ratio, friction_coefficient=self.friction_coefficient,
                 phi_merchant=merchant(self.friction_angle, self.rake),
                 phi_lee_shaffer=lee_shaffer(self.friction_angle, self.rake))
        return d


def merchant(friction_angle: float, rake: float) -> float:
    """Merchant's shear angle ``pi/4 - (lambda - alpha)/2`` (minimum energy, perfectly plastic)."""
    return math.pi / 4 - 0.5 * (friction_angle - rake)


def lee_shaffer(friction_angle: float, rake: float) -> float:
    """Lee and Shaffer's shear angle ``pi/4 - (lambda - alpha)`` (slip-line field, rigid-plastic)."""
    return math.pi / 4 - (friction_angle - rake)


def shear_plane_forces(k: float, phi: float, friction_angle: float, cut: Cut) -> tuple[float, float, float]:
    """(F_c, F_t, t2) of a thin shear plane at ``phi`` carrying the shear flow stress ``k`` [Pa], with the
    friction angle ``lambda`` on the rake face (Merchant's force circle): the classic models' forces."""
    fs = k * cut.uncut * cut.width / math.sin(phi)
    r = fs / math.cos(phi + friction_angle - cut.rake)
    return (r * math.cos(friction_angle - cut.rake), r * math.sin(friction_angle - cut.rake),
            cut.uncut * math.cos(phi - cut.rake) / math.sin(phi))


def _partition(x: float) -> float:
    """Boothroyd's share of the shear plane heat conducted into the workpiece at ``x = R_T tan(phi)``."""
    x = max(x, 0.04)
    return 0.5 - 0.35 * math.log10(x) if x <= 10.0 else 0.3 - 0.15 * math.log10(x)


def _bracket(f, x0: float, step: float, lo: float, hi: float, falling: bool | None):
    """An interval around ``x0`` within [lo, hi] where ``f`` changes sign, stepping away from ``x0`` with a
    growing step; ``falling=True`` looks for a + to - change (in x), None for a change either way (the
    direction from the local slope). ``(x0, x0)`` when ``x0`` is a root already; None if not found."""
    f0 = f(x0)
    if f0 != f0:
        return None
    if abs(f0) < 1e-11:
        return (x0, x0)
    if falling is None:
        x1 = x0 + step if x0 + step <= hi else x0 - step
        f1 = f(x1)
        if f1 != f1:
            return None
        if f0 * f1 <= 0:
            return (min(x0, x1), max(x0, x1))
        falling = (f1 - f0) / (x1 - x0) < 0
    up = f0 > 0 if falling else f0 < 0       # is the root above x0?
    a = x0
    for _ in range(40):
        b = min(a + step, hi) if up else max(a - step, lo)
        fb = f(b)
        if fb != fb:
            return None
        if fb * f0 <= 0:
            return (a, b) if up else (b, a)
        if b in (lo, hi):
            return None
        a, f0, step = b, fb, step * 1.6
    return None


def _fixed_point(G, x0: float, lo: float, hi: float) -> dict:
    """Solve ``x = G(x)["T"]`` (a temperature) by secant steps on ``G(x) - x``, kept inside [lo, hi] and
    falling back to the plain iteration when a secant step leaves it; returns G at the solution."""
    g0 = G(x0)
    x1 = g0["T"]
    r0 = x1 - x0
    for _ in range(100):
        g1 = G(x1)
        r1 = g1["T"] - x1
        if abs(r1) < 1e-12 * x1:
            return g1
        x2 = x1 - r1 * (x1 - x0) / (r1 - r0) if r1 != r0 else g1["T"]
        if not lo <= x2 <= hi:
            x2 = g1["T"]
        x0, r0, x1 = x1, r1, x2
    raise OxleyError("the temperature fixed point of the Oxley model did not converge in 100 steps")


def _root(f, bracket: tuple[float, float] | None) -> float | None:
    """Brent's root in ``bracket``; None when the bracket does not hold a sign change (re-evaluated: with
    warm starts a residual far from its own root is reproduced only to round-off) or meets a NaN."""
    if bracket is None:
        return None
    a, b = bracket
    if a == b:
        return a
    try:
        return brentq(f, a, b, xtol=1e-10, rtol=1e-12)
    except ValueError:
        return None


class _Model:
    """The model's equations at one (phi, C0, delta); counts its evaluations."""

    def __init__(self, mat: JohnsonCook, th: ThermalProperties, cut: Cut, opt: Options):
        self.mat, self.th, self.cut, self.opt = mat, th, cut, opt
        self.T_chip_of = PROPERTY_TEMPERATURES[opt.properties]
        self.evaluations = 0
        self._primary_cache: dict = {}
        self.last_phi: float | None = None    # warm starts of the root searches
        self.last_C0: float | None = None
        self.last_T_AB: float | None = None   # warm starts of the temperature fixed points
        self.last_T_prop: float | None = None

    def primary(self, phi: float, C0: float) -> dict:
        """Shear plane AB: strain, rate, temperature (fixed point), flow stress, forces."""
        key = (phi, C0)
        if key in self._primary_cache:
            return self._primary_cache[key]
        mat, th, cut = self.mat, self.th, self.cut
        a = cut.rake
        l_ab = cut.uncut / math.sin(phi)
        v_s = cut.speed * math.cos(a) / math.cos(phi - a)
        eps = math.cos(a) / (2.0 * SQRT3 * math.sin(phi) * math.cos(phi - a))
        rate = C0 * v_s / (SQRT3 * l_ab)
        def heat(T):
            k = mat.flow_stress(eps, rate, T) / SQRT3
            beta = _partition(th.thermal_number(T, cut.speed, cut.uncut) * math.tan(phi))
            dT_sz = (1.0 - beta) * k * l_ab * math.cos(a) / (th.rho * th.c(T) * cut.uncut * math.cos(phi - a))
            return dict(k=k, beta=beta, dT_sz=dT_sz, T=min(cut.T_work + self.opt.eta * dT_sz, mat.T_melt))

        h = _fixed_point(heat, self.last_T_AB or cut.T_work, cut.T_work, mat.T_melt)
        self.last_T_AB = h["T"]
        T, k, beta, dT_sz = h["T"], h["k"], h["beta"], h["dT_sz"]
        fs = k * l_ab * cut.width
        out = dict(eps=eps, rate=rate, T_AB=T, k_AB=k, Fs=fs, beta=beta, dT_sz=dT_sz, n_eq=mat.n_eq(eps))
        self._primary_cache[key] = out
        return out

    def state(self, phi: float, C0: float, delta: float) -> dict:
        """Every quantity of the model at (phi, C0, delta), with the two residuals."""
        self.evaluations += 1
        mat, th, cut = self.mat, self.th, self.cut
        a, t1, w = cut.rake, cut.uncut, cut.width
        p = self.primary(phi, C0)
        cn = C0 * p["n_eq"]
        tan_theta = 1.0 + 2.0 * (math.pi / 4 - phi) - cn
        theta = math.atan(tan_theta)
        lam = theta + a - phi
        R = p["Fs"] / math.cos(theta)
        F, N = R * math.sin(lam), R * math.cos(lam)
        t2 = t1 * math.cos(phi - a) / math.sin(phi)
        v_c = cut.speed * math.sin(phi) / math.cos(phi - a)
        h = t1 * math.sin(theta) / (math.cos(lam) * math.sin(phi)) * (1.0 + cn / (3.0 * tan_theta))
        if not (tan_theta > 0 and h > 0 and math.cos(lam) > 0):
            # the resultant leaves the shear plane's range: no chip flow at these (phi, C0)
            return dict(p, phi=phi, C0=C0, delta=delta, res_phi=math.nan, res_C0=math.nan, Fc=math.nan)
        T_int = T_chip = cut.T_work + p["dT_sz"]
        if F > 0:
            def chip(T_prop):
                dT_c = F * math.sin(phi) / (th.rho * th.c(T_prop) * t1 * w * math.cos(phi - a))
                x = th.thermal_number(T_prop, cut.speed, t1) * t2 / h
                dT_m = dT_c * 10.0 ** (0.06 - 0.195 * delta * math.sqrt(x) + 0.5 * math.log10(x))
                T_chip = cut.T_work + p["dT_sz"] + dT_c
                T_int = cut.T_work + p["dT_sz"] + self.opt.psi * dT_m
                return dict(T_chip=T_chip, T_int=T_int,
                            T=min(self.T_chip_of(p["T_AB"], T_chip, T_int), mat.T_melt))

            c = _fixed_point(chip, self.last_T_prop or p["T_AB"], cut.T_work, mat.T_melt)
            self.last_T_prop = c["T"]
            T_chip, T_int = c["T_chip"], c["T_int"]
        eps_int = 2.0 * p["eps"] + 0.5 * h / (SQRT3 * delta * t2)
        rate_int = v_c / (SQRT3 * delta * t2)
        k_int = mat.flow_stress(eps_int, rate_int, T_int) / SQRT3
        tau_int = F / (h * w)
        sigma_n = N / (h * w)
        sigma_n_tip = p["k_AB"] * (1.0 + math.pi / 2 - 2.0 * a - 2.0 * cn)
        return dict(p, phi=phi, C0=C0, delta=delta, theta=theta, lam=lam, R=R, F=F, N=N, t2=t2, h=h,
                    Fc=R * math.cos(lam - a), Ft=R * math.sin(lam - a), T_int=T_int, T_chip=T_chip,
                    eps_int=eps_int, rate_int=rate_int, k_int=k_int, tau_int=tau_int, sigma_n=sigma_n,
                    res_phi=(tau_int - k_int) / p["k_AB"], res_C0=(sigma_n - sigma_n_tip) / p["k_AB"])

    def phi_for(self, C0: float, delta: float) -> float | None:
        """The shear angle where tau_int = k_int: the largest root in phi_range (None if there is none).

        A call starts from the last root (the solution moves little with C0 and delta) and steps away from
        it until the sign changes; the first call, or one where that fails, scans down from phi_max in
        1 deg steps."""
        f = lambda phi: self.state(phi, C0, delta)["res_phi"]
        root = None
        if self.last_phi is not None:
            lo, hi = self.opt.phi_range
            root = _root(f, _bracket(f, self.last_phi, math.radians(0.25), lo, hi, falling=True))
        if root is None:
            root = self._phi_scan(f)
        if root is not None:
            self.last_phi = root
        return root

    def _phi_scan(self, f) -> float | None:
        lo, hi = self.opt.phi_range
        b, fb = hi, f(hi)
        while b > lo:
            a = max(b - math.radians(1.0), lo)
            fa = f(a)
            if fa > 0 >= fb:           # NaN (no valid state) compares False: skipped
                root = _root(f, (a, b))
                if root is not None:
                    return root
            b, fb = a, fa
        return None

    def C0_for(self, delta: float) -> float | None:
        """The strain-rate constant where the interface normal stress balances the one at the tool tip."""
        def g(C0):
            phi = self.phi_for(C0, delta)
            return math.nan if phi is None else self.state(phi, C0, delta)["res_C0"]

        lo, hi = self.opt.C0_range
        root = None
        if self.last_C0 is not None:
            root = _root(g, _bracket(g, self.last_C0, 0.05, lo, hi, falling=None))
        if root is None:
            grid = [lo + (hi - lo) * i / 8 for i in range(9)]
            vals = [g(c) for c in grid]
            for (c0, v0), (c1, v1) in zip(zip(grid, vals), zip(grid[1:], vals[1:])):
                if v0 * v1 <= 0:       # False with a NaN
                    root = _root(g, (c0, c1))
                    if root is not None:
                        break
        if root is not None:
            self.last_C0 = root
        return root

    def solve_delta(self, delta: float) -> dict | None:
        C0 = self.C0_for(delta)
        if C0 is None:
            return None
        phi = self.phi_for(C0, delta)
        return None if phi is None else self.state(phi, C0, delta)


def predict(material: JohnsonCook, thermal: ThermalProperties, cut: Cut, options: Options = Options()) -> Result:
    """Solve the extended Oxley model for one cut; raises :class:`OxleyError` without a solution."""
    t0 = time.perf_counter()
    if not (0 < cut.uncut and 0 < cut.width and 0 < cut.speed and abs(cut.rake) < math.radians(45)):
        raise OxleyError("the cut needs positive speed, uncut chip thickness and width, and |rake| < 45 deg")
    model = _Model(material, thermal, cut, options)

    def cutting_force(delta):
        s = model.solve_delta(delta)
        return math.inf if s is None or not math.isfinite(s["Fc"]) else s["Fc"]

    lo, hi = options.delta_range
    # F_c(delta) is smooth with one minimum; a coarse scan keeps Brent inside a bracket with a solution
    grid = [lo + (hi - lo) * i / 6 for i in range(7)]
    vals = [cutting_force(d) for d in grid]
    i = min(range(len(grid)), key=vals.__getitem__)
    if not math.isfinite(vals[i]):
        raise OxleyError(f"no Oxley solution for shear angles {math.degrees(options.phi_range[0]):g}-"
                         f"{math.degrees(options.phi_range[1]):g} deg, C0 {options.C0_range[0]:g}-"
                         f"{options.C0_range[1]:g}, delta {lo:g}-{hi:g} (V = {cut.speed:g} m/s, "
                         f"t1 = {cut.uncut:g} m, rake {math.degrees(cut.rake):g} deg)")
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    penalty = 10.0 * max(v for v in vals if math.isfinite(v))       # Brent's parabolas need finite values
    best = minimize_scalar(lambda d: min(cutting_force(d), penalty), bounds=(a, b), method="bounded",
                           options={"xatol": 2e-5})
    delta = best.x if best.fun <= vals[i] else grid[i]
    s = model.solve_delta(delta)
    if s is None or not math.isfinite(s["Fc"]):
        delta, s = grid[i], model.solve_delta(grid[i])
    if s is None or not math.isfinite(s["Fc"]):
        raise OxleyError(f"the Oxley solution found at delta = {delta:g} was not reproduced (V = {cut.speed:g} m/s, "
                         f"t1 = {cut.uncut:g} m, rake {math.degrees(cut.rake):g} deg)")
    return Result(Fc=s["Fc"], Ft=s["Ft"], chip_thickness=s["t2"], phi=s["phi"], friction_angle=s["lam"],
                  theta=s["theta"], C0=s["C0"], delta=delta, contact_length=s["h"], T_AB=s["T_AB"],
                  T_int=s["T_int"], T_chip=s["T_chip"], k_AB=s["k_AB"], k_int=s["k_int"], sigma_N=s["sigma_n"],
                  strain_AB=s["eps"], rate_AB=s["rate"], strain_int=s["eps_int"], rate_int=s["rate_int"],
                  beta=s["beta"], Fs=s["Fs"], F=s["F"], N=s["N"], rake=cut.rake, uncut=cut.uncut,
                  inertia=thermal.rho * (cut.speed * math.cos(cut.rake) / math.cos(s["phi"] - cut.rake)) ** 2 / s["k_AB"],
                  kinetic=0.5 * thermal.rho * (cut.speed * math.sin(s["phi"]) / math.cos(s["phi"] - cut.rake)) ** 2
                  * cut.width * cut.uncut / s["Fc"],
                  width=cut.width, evaluations=model.evaluations, seconds=time.perf_counter() - t0)


# The regression case of Lalwani et al. (2009), AISI 1045 after Jaspers and Dautzenberg (2002):
# Johnson-Cook constants with T_room = 25 C, T_melt = 1460 C; k and c linear in T (in C).
AISI1045_LALWANI = JohnsonCook(A=553.1e6, B=600.8e6, n=0.234, C=0.0134, m=1.0, T_melt=1460.0 + 273.15,
                               T_room=25.0 + 273.15)
AISI1045_LALWANI_THERMAL = ThermalProperties(rho=8000.0, k0=52.61, c0=420.0, T0=273.15, k_slope=-0.0281,
                                             c_slope=0.504)
