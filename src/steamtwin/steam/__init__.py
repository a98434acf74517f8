"""Water and steam properties.

- :mod:`steamtwin.steam.if97`: IAPWS-IF97 properties (vectorised, validated; via CoolProp).
- :mod:`steamtwin.steam.tables`: fast spline-table look-up for superheated steam, for numba
  kernels (IAPWS G13-15 SBTL idea).

Submodules are not imported here so that importing the table kernels does not load CoolProp.
"""
