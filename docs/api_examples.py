"""A short example per module of the API reference (docs/conf.py puts each on its module's page;
tests/test_docs.py runs every one, so they cannot rot)."""

EXAMPLES = {
    "tippedisk_analysis": '''
import tippedisk_analysis as td

# Table 3 start, Sect. 6 parameters, ODE Model 1
ds = td.simulate("ode-euler", 1.0)
# completed, the height of S [m] at 1 s
print(ds.attrs["status"], float(ds.z_S[-1]))
td.save(ds, "run.nc")
# refuses a file that is not a dataset of the package
again = td.load("run.nc")
disk = td.Disk(m=0.4, e=0.002, r=0.04, A=2e-4, B=1.8e-4, C=3.7e-4)
# Moreau Model 1, set-valued Coulomb
quick = td.simulate("m1", 0.2, setup=td.Setup(disk=disk), dt=1e-4)
''',
    "tippedisk_analysis.dynamics": '''
import heyoka as hy
from tippedisk_analysis import dynamics as dy

# the Brusselator: an equilibrium (a, b/a), a Hopf point at b = 1 + a^2
x, y = hy.make_vars("x", "y")
a, b = hy.par[0], hy.par[1]
rhs = (a - (b + 1) * x + x * x * y, b * x - x * x * y)
bruss = dy.System("brusselator", (x, y), rhs, {"a": 1.0, "b": 1.5})
eq = dy.equilibrium_branch(bruss, [1.0, 1.5], "b", bounds=(1.5, 3.0))
# the orbits born at b = 2, by collocation
orbits = dy.orbit_branch(bruss, eq, "HOPF1", bounds=(1.5, 2.5))
# the last one again by shooting, from its first point
orbit = dy.find_orbit(bruss, orbits.initial_state.values[-1], float(orbits.period[-1]),
                      bruss.with_pars(b=2.5))
print(eq.attrs["labels"], orbits.attrs["status"], orbit.period)
''',
    "tippedisk_analysis.analysis.stationary": '''
from tippedisk_analysis.analysis import stationary

# reduced states (7, 2) at two spin rates
states = stationary.stationary_state("inverted", [20.0, 40.0])
print(states[:, 1])
''',
    "tippedisk_analysis.analysis.stability": '''
from tippedisk_analysis.analysis import stability
from tippedisk_analysis.models import ode

# Tables 1-3, eps = 0.1 m/s
pars = ode.parameter_vector()
# > 0: unstable at 40 rad/s
print(stability.max_real_eig("inverted", 40.0, pars))
''',
    "tippedisk_analysis.analysis.maps": '''
from tippedisk_analysis.analysis import maps

smap = maps.stability_map(omega=[20, 30, 40], eps=[0.1, 0.25], progress=False)
# flags: 0 stable, 1 marginal, 2 unstable
print(smap.stability.sel(branch="inverted").values)
''',
    "tippedisk_analysis.analysis.spin_continuation": '''
from tippedisk_analysis.analysis import spin_continuation

import tippedisk_analysis as td

setup = td.Setup(friction=td.Friction(eps=0.25))
branch = spin_continuation.continue_branch("inverted", "omega", 20.0, 60.0, setup=setup)
# the Hopf and zero-eigenvalue points on it
print(branch.attrs["message"])
''',
    "tippedisk_analysis.analysis.reduced": '''
import numpy as np
from tippedisk_analysis.analysis import reduced, stationary
from tippedisk_analysis.models import ode

x = stationary.stationary_state("inverted", [40.0])[:, 0]
# an equilibrium: 0
print(np.abs(reduced.evaluate(x[:, None], ode.parameter_vector())["rhs"]).max())
''',
    "tippedisk_analysis.analysis.orbits": '''
import tippedisk_analysis as td
from tippedisk_analysis.analysis import orbits

# periodic orbits exist only without friction
frictionless = td.Setup(friction=td.Friction(mu=0.0))
orbit = orbits.tippedisk_lyapunov_orbit(frictionless, "inverted", 40.0)
print(orbit.message)
''',
    "tippedisk_analysis.analysis.lyapunov": '''
from tippedisk_analysis.analysis import lyapunov

spectrum = lyapunov.textbook_spectrum("lorenz", [1.0, 1.0, 1.0], t_end=200.0)
print(spectrum.exponents.values)                                   # about 0.9, 0, -14.6
''',
    "tippedisk_analysis.analysis.poincare": '''
from tippedisk_analysis.analysis import poincare

# Table 3 run, upward crossings
sec = poincare.poincare_section("beta_dot=0", t_end=3.0)
print(sec.sizes["crossing"], sec.attrs["status"])
''',
    "tippedisk_analysis.analysis.outcome_map": '''
from tippedisk_analysis.analysis.outcome_map import outcome_map

omap = outcome_map({"omega": (20, 60, 3), "eps": (0.1, 0.2, 2)}, t_end=2.0,
                   progress=False)
print(omap.outcome.attrs["flag_meanings"], omap.outcome.values)
''',
    "tippedisk_analysis.analysis.basins": '''
from tippedisk_analysis.analysis import basins

# 2 x 2 starts at Omega = 40 rad/s
ds = basins.basins({"beta0": (1.4, 1.7, 2), "dgamma0": (-0.5, 0.5, 2)},
                   initial={"omega": 40.0}, parameters={"eps": 0.25}, progress=False)
print(ds.attrs["message"])
''',
    "tippedisk_analysis.analysis.bifurcation": '''
from tippedisk_analysis.analysis import bifurcation

diagram = bifurcation.bifurcation_diagram([30.0, 40.0], t_end=3.0, t_transient=1.0,
                                          progress=False)
# gamma at the crossings of beta_dot = 0
print(diagram.sizes["point"])
''',
    "tippedisk_analysis.analysis.rolling": '''
from tippedisk_analysis.analysis import rolling

# the rolling disk's spin: its eigenvalues
print(rolling.spin_eigenvalues("inverted", [40.0])[0])
''',
    "tippedisk_analysis.analysis.inversion": '''
from tippedisk_analysis.analysis import inversion

# one run: does the Table 3 start invert at 36 rad/s (z_S > r + 0.8 e)?
print(inversion.outcome(36.0))
# the initial spin above which it does, bracketed by two runs 0.01 rad/s apart
th = inversion.spin_threshold(bracket=(30.0, 36.0), scan=4, xtol=0.01)
print(th.status, th.low, th.high)
# the same with the slow flow (rolling + first-order slip), eps = 5 mm/s
slow = inversion.with_eps(None, 0.005)
print(inversion.spin_threshold(model="slow", setup=slow, bracket=(32.0, 36.0), scan=3, xtol=0.01).message)
# how high S gets (its highest (z_S - r) / e within the horizon): a smooth curve in the initial spin
print(inversion.highest_point(33.5))
print(inversion.highest_points([32.5, 33.5, 34.5]).height.values)
''',
    "tippedisk_analysis.analysis.critical_spin": '''
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.parameters import Disk

found = cs.omega_critical()  # Tables 1-2: the nutation of the inverted spin is damped above omega_c
print(found.message)
# the initial spin whose rolling energy equals the inverted spin's at omega_c (friction's losses neglected; not a bound)
print(cs.initial_spin_threshold(found.omega_critical))
# the answer checks itself: Re lambda / eps of the slow flow's nutation at omega_c (heyoka's Jacobian)
print(cs.check_against_jacobian(found.omega_critical))
# another disk: 4 mm eccentricity, A, B, C about G kept
print(cs.omega_critical(Disk().with_eccentricity(0.004)).omega_critical)
''',
    "tippedisk_analysis.analysis.spin_passage": '''
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.analysis import spin_passage as sp

# Table 3's start at 36 rad/s, eps = 0.02 m/s, run past the inversion (3 / eps seconds or until it falls)
ds = sp.passage(36.0, setup=inversion.with_eps(None, 0.02))
print(ds.attrs["message"])  # when S went up, when it fell back below G, how the run ended
# ln A of the precession over 30 s of the stay, measured and from its linear rate at the current spin
t0 = ds.attrs["t_inverted"] + 5.0
print(sp.integrated_rate(ds, "precession", t0, t0 + 30.0))
''',
    "tippedisk_analysis.analysis.nutation_cycles": '''
from tippedisk_analysis.analysis import nutation_cycles as nc

# the nutation family of the rolling held model at 30.5 rad/s, with each orbit's drift under friction
ds = nc.drift(30.5, max_amplitude=2.0)
print(ds.attrs["message"])  # how many orbits' drift passed its checks
# the nutation cycles: inside the repelling one the nutation decays at this held spin, outside it grows
print(nc.cycles(ds))
''',
    "tippedisk_analysis.analysis.free_nutation": '''
from tippedisk_analysis.analysis import free_nutation as fn

# (N1) at one orbit: the nutation amplitude's and the spin's rates in the slow time eps t
print(fn.rates(1.0, 30.5))
# the averaged path from a = 1.2 rad, Omega0 = 32 rad/s over eps t = 0.1 m
path = fn.averaged_path(1.2, 32.0, 0.1)
print(path.attrs["status"], float(path.amplitude[-1]), float(path.spin[-1]))
''',
    "tippedisk_analysis.plotting": '''
import tippedisk_analysis as td
from tippedisk_analysis.plotting import plot_dataset

ds = td.simulate("ode-euler", 1.0)
# the figure of the dataset's kind
plot_dataset(ds, "run.png")
''',
    "tippedisk_analysis.solvers.moreau": '''
import tippedisk_analysis as td

# Moreau Model 6 (quaternions, smooth Coulomb)
ds = td.simulate("m6", 0.1, dt=1e-4)
# the contacts closed at the end
print(ds.attrs["status"], int(ds.n_closed.values[-1]))
''',
}
