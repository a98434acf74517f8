"""HP rotor thermal stress and fatigue life in deep peak-shaving (issue 23).

The rotor section around the control stage as a 2-D axisymmetric solid (r, z): transient
conduction with steam-side conditions from the FOM, thermo-elastic stress with the centrifugal
load, a transient reduced-order model, fatigue (rainflow, Neuber, Manson–Coffin–Basquin, Miner)
and creep (Larson–Miller) life, and a ramp-rate advisor. ``material`` holds the property
protocol every solver reads. See docs/rotor.md.
"""
