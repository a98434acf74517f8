"""``GET /api/units/{unit}/rotor/advice?to=…``: the ramp advisor's answer from the live twin's
last saved rotor state, at the load measured then — the same as the advisor's own on that
state — and the refusals that say what is missing."""

from __future__ import annotations

import pandas as pd
import pytest
from fastapi.testclient import TestClient
from rotor_fixtures import START, write_rotor_config

from steamtwin.live.config import load_config
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.rotor_stream import LiveRotor
from steamtwin.model.operating import load_profile_inputs
from steamtwin.rotor.advisor import RampAdvisor
from steamtwin.rotor.model import RotorModel, RotorState
from steamtwin.web.app import create_app

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")
ALLOWABLE = 150e6
LOAD = 0.9


@pytest.fixture(scope="module")
def served(tmp_path_factory, reference_spec, reference_model):
    """unit1 with a coarse rotor model file and a saved state: the rotor steady at 90 %."""
    folder = tmp_path_factory.mktemp("advice")
    model = RotorModel(reference_spec, mesh_size=0.08, groove_mesh_size=0.006,
                       training_step_s=60.0, training_hold_s=900.0,
                       fit_ramps=[(1.0, 0.5, 0.05)]).fit()
    model.save(folder / "rotor.npz")
    inputs = load_profile_inputs(reference_spec, [LOAD, LOAD], 1.0)
    inputs.index = START + pd.to_timedelta([0, 1], unit="s")
    live = LiveRotor(model)
    run = reference_model.simulate_detailed(inputs)
    live.advance(reference_model, inputs, run, model.params_)
    rated = reference_spec.design.generator_power
    measured = inputs.assign(load=LOAD * rated)
    flags = pd.DataFrame(None, index=inputs.index, columns=measured.columns, dtype=object)
    with LiveHistorian(folder / "twin.duckdb") as historian:
        historian.commit_block("unit1", {"measured": measured}, flags,
                               state={"rotor": live.get_state()})
    config = write_rotor_config(folder, folder / "twin.duckdb").source
    config.write_text(config.read_text().replace('rotor = "fit"\nrotor_allowable_mpa = 300',
                                                 f'rotor = "rotor.npz"\nrotor_allowable_mpa = '
                                                 f'{ALLOWABLE / 1e6:g}'))
    with TestClient(create_app(folder / "twin.duckdb", load_config(config))) as client:
        yield client, model, live


def test_the_advice_is_the_advisors_from_the_saved_state(served):
    client, model, live = served
    answer = client.get("/api/units/unit1/rotor/advice", params={"to": 0.7, "hold_s": 1800})
    assert answer.status_code == 200, answer.text
    body = answer.json()
    assert body["state_time"] == (START + pd.Timedelta(seconds=1)).isoformat()
    assert body["from_load"] == pytest.approx(LOAD, rel=1e-12)
    expected = RampAdvisor(model, ALLOWABLE).fit().advise(
        RotorState.from_dict(live.get_state()["state"]), LOAD, 0.7, hold_after_s=1800).summary()
    assert body["rate_percent_per_min"] == pytest.approx(expected["rate_percent_per_min"],
                                                         rel=1e-12)
    assert body["limited_by"] == expected["limited_by"]
    assert body["allowable_pa"]["groove"] == [-ALLOWABLE, ALLOWABLE]
    for location in ("groove", "bore"):  # the advised ramp keeps within the allowable
        assert abs(body["peak_pa"][location]) <= ALLOWABLE


def test_advice_refusals_name_what_is_missing(served):
    client, _, _ = served
    answer = client.get("/api/units/unit1/rotor/advice", params={"to": 0.1})
    assert answer.status_code == 422 and "outside" in answer.json()["error"]
    answer = client.get("/api/units/unit1/rotor/advice", params={"to": 2})
    assert answer.status_code == 422 and "to" in answer.json()["error"]
    answer = client.get("/api/units/unit2/rotor/advice", params={"to": 0.5})
    assert answer.status_code == 404 and "no rotor model" in answer.json()["error"]
