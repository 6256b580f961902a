"""Validation cases and the cross-check machinery, without the engine."""

import math

import numpy as np
import pytest

from vibrofeed.models import deck as dm
from vibrofeed.models.part_on_surface import Event
from vibrofeed.validation import cases as C
from vibrofeed.validation.crosscheck import KINDS, check_vertical_case, landing_period, model_flights
from vibrofeed.validation.outcome import Row

# The quantities each kind reports (a case needs a tolerance for each it uses).
QUANTITIES = {"flights": {"landing_time", "flight_duration"}, "transport": {"mean_speed"},
              "climb": {"climbs", "centripetal"}, "chute": {"chute_speed"},
              "period": {"period"}, "vertical": {"net_speed"},
              "replay": {"mean_difference_mm", "mean_abs_error_mm", "final_displacement_mm"},
              "pulloff": {"pulloff"}, "reference": {"parts_per_s"},
              "line_transport": {"section_speed"},
              "line_continuity": {"joint_flux", "little_flux", "feed_flux", "density_ratio"},
              "vdw_pulloff": {"pulloff"}, "sticking": {"leaves"}, "squeeze_launch": {"deficit", "max_gap"},
              "rocking_onset": {"rocks"}, "free_rocking": {"impact_speed", "impact_ratio"},
              "tip_or_slide": {"regime"}}


@pytest.mark.parametrize("name", C.available())
def test_every_case_file_is_complete(name):
    case = C.find(name)
    assert case.kind in KINDS
    assert case.title and case.notes, "a case says what it checks and why its tolerances"
    assert QUANTITIES[case.kind] <= set(case.tolerance)
    if case.compare.get("restitution") == "realised":
        assert "restitution" in case.tolerance
    assert case.points(), "at least one run"
    if case.kind == "replay":  # runs one DEM replay per measured trial instead of a sweep
        assert case.compare["trials"] and set(case.compare["trials"]) == set(case.compare["normal_force_mg"])
        assert {"mass", "mu"} <= set(case.parameters)
        return
    from vibrofeed.validation.crosscheck import CrossCheck
    runs = CrossCheck(case, "/nonexistent").plan()  # parameters pass the deck's checks
    assert len(runs) == len(case.points())
    assert len({r.label for r in runs}) == len(runs), "one output file per run"


def test_at_least_the_required_cases_exist():
    kinds = {C.find(n).kind for n in C.available()}
    assert kinds == set(KINDS)
    phases = {C.find(n).parameters.get("gamma") for n in C.available() if n.startswith("phase_")}
    assert len(phases) >= 2, "phase optimisation at a small and a large Gamma"


def test_sweeps_product_and_zip(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('title = "t"\nkind = "transport"\ndeck = "single_part"\nnotes = "n"\n'
                 "[sweep]\na = [1, 2]\nb = [3, 4]\n[tolerance]\nmean_speed = { rel = 0.02 }\n")
    assert C.load(p).points() == [{"a": 1, "b": 3}, {"a": 1, "b": 4}, {"a": 2, "b": 3}, {"a": 2, "b": 4}]
    p.write_text(p.read_text().replace('notes = "n"', 'notes = "n"\nzip = true'))
    assert C.load(p).points() == [{"a": 1, "b": 3}, {"a": 2, "b": 4}]


@pytest.mark.parametrize("text, fragment", [
    ('kind = "transport"\ndeck = "x"\n', "missing title"),
    ('title = "t"\nkind = "transport"\ndeck = "x"\n[tolerance]\nq = 0.1\n', "abs = x"),
    ('title = "t"\nkind = "transport"\ndeck = "x"\n[tolerance]\nq = { rel = -1 }\n', ">= 0"),
    ('title = "t"\nkind = "transport"\ndeck = "x"\n[sweep]\na = []\n', "non-empty"),
    ('title = "t"\nkind = "transport"\ndeck = "x"\nzip = true\n[sweep]\na = [1]\nb = [1, 2]\n',
     "same length"),
    ("title = \n", "not valid TOML"),
])
def test_malformed_case_files_are_refused(tmp_path, text, fragment):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(C.CaseError, match=fragment):
        C.load(p)


def test_unknown_case():
    with pytest.raises(C.CaseError, match="no validation case nope"):
        C.find("nope")


def test_row_tolerances():
    assert Row("c", "q", 1.0, 1.019, 0.02, "rel").passed
    assert not Row("c", "q", 1.0, 1.021, 0.02, "rel").passed
    assert Row("c", "q", -1.0, -1.019, 0.02, "rel").passed  # relative to |model|
    assert Row("c", "q", 0.5, 0.509, 0.01, "abs").passed
    assert not Row("c", "q", 0.5, 0.511, 0.01, "abs").passed
    assert Row("c", "q", 2, 2, 0, "abs").passed and not Row("c", "q", 2, 1, 0, "abs").passed
    r = Row("c", "q", 2.0, 2.1, 0.1, "rel")
    assert r.rel_diff == pytest.approx(0.05, rel=1e-12)
    assert Row("c", "q", 0.0, 0.01, 0.02, "abs").rel_diff is None  # JSON null, not Infinity
    assert set(r.as_dict()) >= {"case", "quantity", "model", "dem", "rel_diff", "tolerance", "passed"}


def test_sigma_tolerance_is_a_multiple_of_the_combined_error():
    # |dem - model| = 0.29 against 2 sigma of a combined error 0.15 (limit 0.30) and 0.14 (0.28)
    assert Row("c", "q", 10.0, 10.29, 2, "sigma", error=0.15).passed
    assert not Row("c", "q", 10.0, 10.29, 2, "sigma", error=0.14).passed
    assert not Row("c", "q", 10.0, 10.0001, 2, "sigma").passed  # no error known: nothing passes
    assert Row("c", "q", 10.0, 10.3, 2, "sigma", error=0.15).as_dict()["error"] == 0.15


def test_sigma_tolerance_in_a_case_file(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('title = "t"\nkind = "reference"\ndeck = "bulk_feeder"\n'
                 "[tolerance]\nparts_per_s = { sigma = 2 }\n")
    assert C.load(p).tolerance_of("parts_per_s") == C.Tolerance(2.0, "sigma")
    p.write_text(p.read_text().replace("{ sigma = 2 }", "{ sigma = 2, rel = 0.1 }"))
    with pytest.raises(C.CaseError, match="sigma = x"):
        C.load(p)


def test_reference_cases_name_one_sweep_point():
    for name in C.available():
        case = C.find(name)
        if case.kind != "reference":
            continue
        wanted = case.compare["reference"]
        matching = [v for v in case.points() if all(float(v[k]) == float(x) for k, x in wanted.items())]
        assert len(matching) == 1 and len(case.points()) > 1


@pytest.mark.parametrize("params, mass", [
    ({"radius": 1e-3, "density": 3.0}, 4 / 3 * math.pi * 1e-9 * 3.0),          # single-part sphere
    ({"shape": 0, "part_size": 2e-3, "density": 3.0}, 4 / 3 * math.pi * 1e-9 * 3.0),  # bulk sphere
    ({"shape": 1, "part_size": 3e-4, "part_thickness": 1e-4, "density": 2330.0},
     9e-8 * 1e-4 * 2330.0),                                                      # chip: a box
    ({"shape": 2, "part_size": 2e-3, "part_thickness": 1e-3, "density": 1.0},
     math.pi * 1e-6 * 1e-3),                                                     # disc: a cylinder
])
def test_mass_of_every_deck_part(params, mass):
    # abs=0: the masses are 3e-9..2e-8 kg, and approx's default abs=1e-12 kg alone would be 3e-4 of them
    assert dm.mass(params) == pytest.approx(mass, rel=1e-12, abs=0)


def test_landing_period():
    T = 0.02
    one = np.arange(1, 30) * T + 0.3 * T
    assert landing_period(one, T, 5 * T) == 1
    # long and short jumps alternate: landings at 0.3 T and 1.1 T of every second period
    two = np.sort(np.concatenate([np.arange(0, 30, 2) * T + 0.3 * T, np.arange(0, 30, 2) * T + 1.1 * T]))
    assert landing_period(two, T, 5 * T) == 2
    rng = np.random.default_rng(3)
    assert landing_period(np.sort(rng.uniform(0, 30 * T, 40)), T, 5 * T) == 0


def test_model_flights_pair_launches_and_impacts():
    ev = lambda t, kind, **info: Event(t, kind, 0, 0, 0, 0, info)  # noqa: E731
    events = [ev(0.1, "launch"), ev(0.5, "impact", rebound=True), ev(0.52, "impact", rebound=False),
              ev(0.52, "stick"), ev(1.1, "launch"), ev(1.5, "impact", rebound=True),
              ev(1.51, "impact", rebound=True), ev(1.511, "rest"), ev(2.1, "launch")]
    assert model_flights(events, 3.0) == [(0.1, 0.5, "lift-off"), (0.5, 0.52, "rebound"),
                                          (1.1, 1.5, "lift-off"), (1.5, 1.51, "rebound")]


# The deck's waveform vocabulary: amp is the displacement amplitude for every waveform.
@pytest.mark.parametrize("waveform", [0, 1, 2, 3])
def test_deck_waveforms_have_the_requested_amplitude(waveform):
    p = {"waveform": waveform, "freq": 40, "amp_t": 1e-4, "amp_n": 6e-5, "phase": 30, "duty": 0.7}
    wf = dm.waveform(p)
    t = np.linspace(0, wf.period, 20000, endpoint=False)
    x, z = wf.position(t)
    assert (x.max() - x.min()) / 2 == pytest.approx(1e-4, rel=1e-6)
    assert abs(x.mean()) < 1e-9 and abs(z.mean()) < 1e-9  # about the mean position
    if waveform in (0, 1):
        assert (z.max() - z.min()) / 2 == pytest.approx(6e-5, rel=1e-6)


def test_gamma_conversion_round_trip():
    assert dm.gamma_from_amp(dm.amp_from_gamma(2.5, 60), 60) == pytest.approx(2.5, rel=1e-12)
    assert dm.amp_from_gamma(1, 50) == pytest.approx(9.81 / (2 * math.pi * 50) ** 2, rel=1e-12, abs=0)


def test_infeasible_vertical_case_is_refused_clearly():
    base = {"freq": "50", "amp_t": "2e-4", "amp_n": "0", "phase": "0", "waveform": "2",
            "duty": "0.8", "mu": "0.5", "radius": "5e-4", "density": "2330"}
    check_vertical_case({**base, "normal_force": "6e-5"})  # feasible: no exception
    with pytest.raises(C.CaseError, match="infeasible vertical transport"):
        check_vertical_case({**base, "normal_force": "1e-5"})  # below m g / mu


def test_jkr_pulloff_closed_form():
    """1.5 pi gamma R*: two 300 um spheres (R* = 75 um) at 0.05 J/m^2 pull off at
    17.67 uN, one on a flat (R* = 150 um) at twice that."""
    from vibrofeed.validation.crosscheck import jkr_pulloff

    assert jkr_pulloff(0.05, 3e-4, 0) == pytest.approx(1.5 * 3.141592653589793 * 0.05 * 75e-6,
                                                       rel=1e-12, abs=0)  # N, ~1.8e-5
    assert jkr_pulloff(0.05, 3e-4, 0) == pytest.approx(17.671e-6, rel=1e-4)
    assert jkr_pulloff(0.05, 3e-4, 1) == pytest.approx(2 * jkr_pulloff(0.05, 3e-4, 0), rel=1e-12, abs=0)


@pytest.mark.parametrize("params, pulloff", [
    # single-part sphere and flat-faced part; bulk sphere, chip, disc: A R / (6 s^2), A S / (6 pi s^3)
    ({"hamaker": 1e-19, "roughness": 1e-8, "radius": 1e-4}, 1e-19 * 1e-4 / (6 * 1.02e-8 ** 2)),
    ({"hamaker": 1e-19, "roughness": 1e-8, "radius": 1e-4, "face_radius": 5e-5},
     1e-19 * math.pi * 25e-10 / (6 * math.pi * 1.02e-8 ** 3)),
    ({"hamaker": 1e-19, "roughness": 1e-8, "shape": 0, "part_size": 2e-4}, 1e-19 * 1e-4 / (6 * 1.02e-8 ** 2)),
    ({"hamaker": 1e-19, "roughness": 1e-8, "shape": 1, "part_size": 3e-4},
     1e-19 * 9e-8 / (6 * math.pi * 1.02e-8 ** 3)),
    ({"hamaker": 1e-19, "roughness": 1e-8, "shape": 2, "part_size": 2e-4},
     1e-19 * math.pi * 1e-8 / (6 * math.pi * 1.02e-8 ** 3)),
])
def test_adhesion_of_every_deck_part(params, pulloff):
    assert dm.adhesion(params).pulloff == pytest.approx(pulloff, rel=1e-12, abs=0)  # from 1.6e-8 N


def test_the_film_is_under_the_flat_face_when_the_part_has_one():
    sphere = dm.film({"air_viscosity": 1.8e-5, "roughness": 1e-7, "radius": 1e-4})
    face = dm.film({"air_viscosity": 1.8e-5, "roughness": 1e-7, "radius": 1e-4, "face_radius": 5e-5})
    assert (sphere.flat, sphere.radius, face.flat, face.radius) == (False, 1e-4, True, 5e-5)
    assert sphere.viscosity == face.viscosity == 1.8e-5 and sphere.free_flow and face.free_flow
    with pytest.raises(ValueError, match="shape must be 0, 1 or 2"):
        dm.adhesion({"hamaker": 1e-19, "roughness": 0.0, "shape": 3, "part_size": 1e-4})


@pytest.mark.parametrize("name", [n for n in C.available() if C.find(n).kind != "replay"])
def test_every_case_s_runs_resolve_in_the_runner_as_the_case_resolved_them(name, tmp_path):
    """What a case hands its runs is resolved again by the runner (run_deck): it must pass and
    give the values the case analyses (spheres' cases were refused once, for the deck's default
    correct among re-given values)."""
    import warnings

    from vibrofeed.parameters import resolve
    from vibrofeed.validation.crosscheck import CrossCheck

    for run in CrossCheck(C.find(name), tmp_path).plan():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # (the case's own, said when it resolved them)
            again = resolve(run.request.deck, run.request.params)
        assert again == run.params


def test_a_case_holding_a_parameter_idle_at_some_points_does_not_warn_of_it():
    """vdw_sticking keeps its roughness at A = 0, where surface forces are off: by design, so
    validate says nothing of it; any other warning still reaches the user."""
    import warnings

    from vibrofeed.errors import ParameterWarning
    from vibrofeed.parameters import resolve
    from vibrofeed.validation.crosscheck import CrossCheck, held_across_points

    case = C.find("vdw_sticking")
    with warnings.catch_warnings(record=True) as heard:
        warnings.simplefilter("always")
        runs = CrossCheck(case, "/nonexistent").plan()
    assert not [w for w in heard if issubclass(w.category, ParameterWarning)]
    idle = next(r for r in runs if r.values["hamaker"] == 0)
    with pytest.warns(ParameterWarning, match="parameter roughness has no effect"):
        resolve(idle.request.deck, idle.request.params)  # said, outside a case
    with held_across_points(), pytest.warns(ParameterWarning, match="radius=0.15 m is 150 mm"):
        resolve(idle.request.deck, {**idle.request.params, "radius": "0.15"})
