"""CoolProp (~2 s of CPU to import) is loaded on the first IF97 call, not with the model: a GA
worker that unpickles the calibration objective and runs the model never needs it."""

from __future__ import annotations

import subprocess
import sys

CHECK = """
import sys
import steamtwin.calibration.evaluation
import steamtwin.model.fom
from steamtwin.steam import if97
assert "CoolProp" not in sys.modules, "imported with the model"
h = float(if97.enthalpy_pt(16.0e6, 811.15))
assert "CoolProp" in sys.modules
assert 3.3e6 < h < 3.5e6, h  # IAPWS-IF97 steam at 16 MPa, 538 °C: 3 396 kJ/kg
"""


def test_coolprop_is_imported_on_the_first_property_call():
    result = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True,
                            timeout=120, check=False)
    assert result.returncode == 0, result.stderr
