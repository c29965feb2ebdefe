"""skyplan.Airspace: flights reserved as operational intents, checked independently -- every
pair of stored volumes compared with shapely (footprints as lat/lng polygons) and plain
interval tests for the altitudes and times -- and its errors."""

import datetime as dt
import itertools

import pytest

import skyplan

shapely = pytest.importorskip("shapely", reason="needs shapely (installed by .ci/run)")
from shapely.geometry import Polygon  # noqa: E402


def at(seconds):
    """An RFC 3339 instant `seconds` after an hour from now (whole seconds)."""
    t = dt.datetime.now(dt.timezone.utc).replace(microsecond=0) + dt.timedelta(hours=1, seconds=seconds)
    return t.strftime("%Y-%m-%dT%H:%M:%SZ")


def parse(t):
    return dt.datetime.fromisoformat(t.replace("Z", "+00:00"))


def volumes_meet(a, b):
    """Whether two Volume4D dicts share a point: closed intervals, closed polygons."""
    if parse(a["time_start"]["value"]) > parse(b["time_end"]["value"]):
        return False
    if parse(b["time_start"]["value"]) > parse(a["time_end"]["value"]):
        return False
    va, vb = a["volume"], b["volume"]
    if va["altitude_lower"]["value"] > vb["altitude_upper"]["value"]:
        return False
    if vb["altitude_lower"]["value"] > va["altitude_upper"]["value"]:
        return False
    pa = Polygon([(p["lng"], p["lat"]) for p in va["outline_polygon"]["vertices"]])
    pb = Polygon([(p["lng"], p["lat"]) for p in vb["outline_polygon"]["vertices"]])
    return pa.intersects(pb)


def intents_meet(a, b):
    return any(volumes_meet(x, y) for x in a["volumes"] for y in b["volumes"])


@pytest.fixture(scope="module")
def city():
    return skyplan.Planner()


def test_reserve_shifts_or_replans_and_nothing_stored_intersects(city):
    air = skyplan.Airspace("sqlite::memory:")
    first = air.reserve(city, at(0), owner="a")
    assert first["delay_s"] == 0.0 and first["timing"] == "constant_speed"
    assert isinstance(first["plan"], skyplan.Plan) and "space_time" not in first
    # The same route at the same instant: refused, naming the first.
    with pytest.raises(skyplan.Conflict) as refused:
        air.reserve(city, at(0), owner="b")
    assert refused.value.conflicts == [(first["intent"]["id"], 1)]
    assert first["intent"]["id"] in str(refused.value)
    # With a window: the departure moves...
    shifted = air.reserve(city, (at(0), at(1800)), owner="b")
    assert shifted["delay_s"] > 0
    # ... or the route is re-planned in space and time, and arrives no later than shifting.
    replanned = air.reserve(city, {"earliest": at(0), "latest": at(1800)}, owner="c", search="space_time")
    st = replanned["space_time"]
    assert replanned["timing"] == "space_time" and st["arrival_delay_s"] > 0
    # Without a deadline the arrival is proven the earliest.
    assert st["arrival_gap_s"] == 0.0
    assert len(st["route_ne"]) >= 2
    # A deadline already passed: the search (hundreds of states on this route) stops at its
    # first look at the clock, raising Timeout, and nothing is stored.
    with pytest.raises(skyplan.Timeout, match="deadline"):
        air.reserve(city, (at(0), at(1800)), owner="d", search="space_time", deadline_ms=0)
    with pytest.raises(skyplan.BadInput, match="deadline_ms"):
        air.reserve(city, at(0), owner="d", deadline_ms=50)
    stored = air.intents()
    assert [i["owner"] for i in stored] == ["a", "b", "c"]
    for x, y in itertools.combinations(stored, 2):
        assert not intents_meet(x, y), (x["id"], y["id"])
    assert air.conflicts() == []
    # get / delete.
    assert air.get(first["intent"]["id"])["owner"] == "a"
    assert air.delete(first["intent"]["id"])["owner"] == "a"
    assert air.get(first["intent"]["id"]) is None


def test_a_fleet_in_space_and_time_accepts_at_least_as_many_and_intersects_nowhere(city):
    # Twelve flights between the corners of the city's middle, all leaving in the same minute.
    places = [(0, 0), (420, 390), (-200, 300), (300, -250), (150, 150), (-150, -200)]
    missions = [
        {"id": f"m{k}", "start_ne": list(a), "goal_ne": list(b), "departure": k % 3, "window_s": 300}
        for k, (a, b) in enumerate(itertools.permutations(places, 2))
        if k < 12
    ]
    reports = {}
    for mode in ("space_time", "shift", "reject_on_conflict"):
        air = skyplan.Airspace("sqlite::memory:")
        report = air.fleet(city, missions, mode=mode, start=at(0))
        assert report["mode"] == mode and report["conflicts"] == 0
        stored = air.intents()
        accepted = [f for f in report["flights"] if f["status"] == "accepted"]
        assert len(stored) == len(accepted) == report["summary"]["accepted"]
        for x, y in itertools.combinations(stored, 2):
            assert not intents_meet(x, y), (mode, x["id"], y["id"])
        reports[mode] = report["summary"]
    assert reports["space_time"]["accepted"] >= reports["shift"]["accepted"] >= reports["reject_on_conflict"]["accepted"]
    assert reports["space_time"]["hovering"] + reports["space_time"]["detoured"] > 0
    # A deadline already passed: the searches that need more than a few hundred states stop,
    # their flights timed out with nothing stored.
    air = skyplan.Airspace("sqlite::memory:")
    report = air.fleet(city, missions, mode="space_time", start=at(0), deadline_ms=0)
    timed_out = [f for f in report["flights"] if f["status"] == "timed_out"]
    assert report["summary"]["timed_out"] == len(timed_out) >= 1
    assert all("deadline" in f["message"] and f["intent_id"] is None for f in timed_out)
    assert len(air.intents()) == report["summary"]["accepted"]
    with pytest.raises(skyplan.BadInput, match="deadline_ms"):
        air.fleet(city, missions, mode="shift", deadline_ms=50)


@pytest.mark.parametrize(
    "kwargs, want",
    [
        ({"departure": "tomorrow"}, "departure"),
        ({"departure": "2020-01-01T00:00:00Z"}, "in the past"),
        ({"departure": at(0), "priority": 101}, "priority: 101"),
        ({"departure": at(0), "owner": "  "}, "owner"),
        ({"departure": at(0), "search": "sideways"}, "search: expected"),
        ({"departure": at(0), "alt_m": "high"}, "alt_m"),
    ],
)
def test_bad_reservations_raise_bad_input_naming_the_field(city, kwargs, want):
    air = skyplan.Airspace("sqlite::memory:")
    with pytest.raises(skyplan.BadInput, match=want):
        air.reserve(city, **kwargs)
    assert air.intents() == []


def test_bad_stores_and_fleets_are_refused(city, tmp_path):
    with pytest.raises(skyplan.BadInput, match="mysql"):
        skyplan.Airspace("mysql://x")
    with pytest.raises(skyplan.AirspaceUnavailable):
        skyplan.Airspace("postgres://nobody@127.0.0.1:1/none?connect_timeout=1")
    air = skyplan.Airspace(f"sqlite:{tmp_path / 'air.sqlite'}")
    import numpy as np

    homeless = skyplan.Planner(np.zeros((20, 20)))
    with pytest.raises(skyplan.BadInput, match="no geodetic home"):
        air.reserve(homeless, at(0), start=(0.5, 0.5), goal=(15.5, 15.5))
    with pytest.raises(skyplan.BadInput, match="mode"):
        air.fleet(city, [], mode="fast")
    with pytest.raises(skyplan.BadInput, match=r"missions\[0\]"):
        air.fleet(city, [{"start_ne": [0, 0], "goal_ne": [420, 390], "priority": 500}])
    assert air.intents() == []
