"""HP rotor thermal stress and fatigue life in deep peak-shaving (issue 23).

The rotor section around the control stage as a 2-D axisymmetric solid (r, z): transient
conduction with steam-side conditions from the FOM, thermo-elastic stress with the centrifugal
load, a transient reduced-order model, fatigue (rainflow, Neuber, Manson–Coffin–Basquin, Miner)
and creep (Larson–Miller) life, and a ramp-rate advisor. ``material`` holds the property
protocol every solver reads. See docs/rotor.md.

The usual path, SI throughout::

    model = RotorModel(spec).fit(params)              # mesh, FEM, stress map, transient ROM
    run = model.simulate(inputs, params)              # groove/bore temperature (K), stress (Pa)
    life = rotor_life(run.frame, model.steel, load=load_fraction)   # fatigue + creep damage
    advice = RampAdvisor(model, allowable=400e6).fit().advise(run.state, 0.5, 0.3)

The public objects, imported on first use:
"""

from steamtwin.lazy import lazy_exports

_EXPORTS = {
    "RotorModel": "steamtwin.rotor.model",
    "RotorState": "steamtwin.rotor.model",
    "RotorRun": "steamtwin.rotor.model",
    "rotor_life": "steamtwin.rotor.life",
    "RotorLife": "steamtwin.rotor.life",
    "RampAdvisor": "steamtwin.rotor.advisor",
    "RampAdvice": "steamtwin.rotor.advisor",
    "rotor_stress": "steamtwin.rotor.report",
    "rotor_geometry": "steamtwin.rotor.geometry",
    "ConstantMaterial": "steamtwin.rotor.material",
    "RotorMaterial": "steamtwin.rotor.material",
}

__all__ = [*_EXPORTS]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
