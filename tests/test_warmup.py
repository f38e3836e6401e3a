"""discover on warm-up campaigns (#13): data made by `rapidcomp simulate
--times` (Pinocchio on the profile the effects are written as, each round at
s(t) times the thermal values: code separate from discover's linear thermal
model), hidden static and thermal effects and a hidden tau."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from rapidcomp.discover.effects import catalogue
from rapidcomp.discover.measured import read_measured
from rapidcomp.discover.model import ParamModel
from rapidcomp.discover.select import discover
from rapidcomp.discover.warmup import estimate
from rapidcomp.kinematics.profile import ThermalProfile, read_profile
from rapidcomp.kinematics.robot import irb140

from conftest import FIXTURES

TIMES = "0,8,16,25,35,50,70,100,140,200"


def _rapidcomp(*args, cwd):
    return subprocess.run([sys.executable, "-m", "rapidcomp", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True)


def _campaign(tmp_path, name, *extra, points="random:30", times=TIMES):
    path = tmp_path / name
    r = _rapidcomp("simulate", "-o", path, "--points", points, "--tool", "0,0,150", "--seed", "4",
                   "--times", times, "--noise", "0.005", *extra, "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    return path


def _discover(path):
    robot = irb140()
    data = read_measured(path)
    model = ParamModel(robot, ThermalProfile(()), data.q_deg, (0, 0, 150))
    return discover(model, data, catalogue(robot))


def test_static_and_thermal_effects_are_told_apart_and_tau_is_found(tmp_path):
    """A J3 zero error (static) and a J2 origin shift and an upper-arm
    elongation that grow as the robot warms (tau 35 min): tau within 10 %,
    its interval holding the truth, each effect named with its kind."""
    path = _campaign(tmp_path, "wu.csv", "--tau-heat", "35", "--effect", "joint_offset:J3=0.01",
                     "--thermal-effect", "joint_displacement:J2=0.03,0,0.04",
                     "--thermal-effect", "link_elongation:J2-J3=0.0002")
    d = _discover(path)
    assert abs(d.warmup.tau_min - 35) < 3.5 and d.warmup.low_min <= 35 <= d.warmup.high_min
    assert d.noise.kind == "replicates" and 0.004 < d.sigma_mm < 0.006
    named = {s.effect.id for s in d.steps}
    assert named == {"joint_offset:J3", "thermal:joint_displacement:J2",
                     "thermal:link_elongation:J2-J3"}
    assert d.verdict == "explained"
    ev = d.thermal_evidence
    assert ev["joint_offset:J3"].startswith("static: as a thermal effect the fit is worse")
    assert ev["thermal:link_elongation:J2-J3"].startswith("thermal: as a static effect")
    got = {s.effect.id: s.params for s in d.steps}
    assert got["thermal:link_elongation:J2-J3"]["epsilon"] == pytest.approx(2e-4, rel=0.1)
    assert got["joint_offset:J3"]["offset_deg"] == pytest.approx(0.01, abs=5e-4)


def test_a_campaign_without_warm_up_names_everything_static(tmp_path):
    """Nothing changes over time: every effect static, and the profile
    discover writes is marked so (fix --transient refuses it)."""
    path = _campaign(tmp_path, "cold.csv", "--tau-heat", "35",
                     "--effect", "joint_offset:J3=0.01")
    d = _discover(path)
    assert d.warmup.tau_min is None and "nothing changes over time" in d.warmup.text
    assert [s.effect.id for s in d.steps] == ["joint_offset:J3"]
    assert not any(s.effect.thermal for s in d.steps)
    r = _rapidcomp("discover", path, "--tool", "0,0,150", "--out-profile", "p.csv", cwd=tmp_path)
    assert r.returncode == 0 and "nothing changed over time" in r.stdout, r.stderr
    assert read_profile(tmp_path / "p.csv").static_only


def test_tau_alone_from_the_data_without_any_effect_model():
    """The model-free estimate on hand-made curves: three poses moving as
    a + (1 - exp(-t/50)) b, 2 um noise."""
    rng = np.random.default_rng(3)
    t = np.repeat([0, 10, 20, 40, 60, 90, 130, 180.0], 3)
    q = np.tile(np.array([[0, 10, 20, 0, 30, 0], [40, 0, 10, 5, 60, 0], [-30, 20, 0, 0, 45, 0]],
                         float), (8, 1))
    b = np.tile(np.array([[0.05, -0.02, 0.08], [0.1, 0.0, -0.04], [0.0, 0.06, 0.02]]), (8, 1))
    xyz = 500 + (1 - np.exp(-t / 50))[:, None] * b + rng.normal(0, 0.002, (24, 3))
    w = estimate(q, xyz, t)
    assert abs(w.tau_min - 50) < 5 and w.sigma_mm == pytest.approx(0.002, rel=0.35)


def test_cli_json_profile_with_tau_and_fix_transient_takes_it(tmp_path):
    path = _campaign(tmp_path, "wu.csv", "--tau-heat", "35", "--effect", "joint_offset:J3=0.01",
                     "--thermal-effect", "joint_displacement:J2=0.03,0,0.04")
    r = _rapidcomp("discover", path, "--tool", "0,0,150", "--json", "d.json", "--report", "d.md",
                   "--out-profile", "thermal.csv", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "d.json").read_text())
    assert 31.5 < doc["tau_min"] < 38.5
    kinds = {s["effect"]: s["thermal"] for s in doc["steps"]}
    assert kinds == {"joint_offset:J3": False, "joint_displacement:J2": True}
    assert "warm-up time constant tau" in r.stdout and "## Warm-up" in (tmp_path / "d.md").read_text()
    assert "joint_offset:J3 is static" in r.stdout
    prof = read_profile(tmp_path / "thermal.csv")
    assert prof.tau_heat_min == pytest.approx(doc["tau_min"], rel=1e-3)
    assert prof.terms("J3").is_zero and not prof.get("J2").is_zero
    fixed = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", "thermal.csv", "--transient",
                       "--limit", "J5=-120:120", "-o", "c.mod", cwd=tmp_path)
    assert fixed.returncode == 0, fixed.stderr
    assert f"heating tau {prof.tau_heat_min:g} min" in fixed.stdout


@pytest.mark.parametrize("args, message", [
    (["--thermal-effect", "joint_offset:J2=0.01"], "--thermal-effect needs --times"),
    (["--times", "0,10,20"], "--times needs --tau-heat"),
    (["--times", "0,10,x", "--tau-heat", "30"], "expected minutes"),
    (["--times", "0,10,20", "--tau-heat", "30", "--thermal-effect", "joint_scale:J2=0.001"],
     "heat does not change a joint scale"),
    # (A new user's: every row stood 30 min, and discover's cooling tau
    # came out at its search range's edge.)
    (["--times", "+30,0,20,40", "--tau-heat", "30"],
     "--times +30,0,20,40: a stop (+N) follows a measurement round; the first round is the "
     "cold start"),
])
def test_bad_campaign_options_exit_2(tmp_path, args, message):
    r = _rapidcomp("simulate", "-o", tmp_path / "x.csv", *args, cwd=tmp_path)
    assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "x.csv").exists()


def test_a_campaign_with_nothing_thermal_says_so(tmp_path):
    """--times with no --thermal-effect (the README's stop example as a new
    user ran it, its profile static): simulated all the same, and a note
    says nothing in it changes with time; with a thermal effect, no note."""
    r = _rapidcomp("simulate", "-o", tmp_path / "x.csv", "--times", "0,20,+30,40",
                   "--tau-heat", "35", "--points", "random:6", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert ("note: --times without --thermal-effect: nothing in this campaign changes with "
            "time (--effect and --profile are static), its rounds are replicates") in r.stdout
    r = _rapidcomp("simulate", "-o", tmp_path / "y.csv", "--times", "0,20,+30,40",
                   "--tau-heat", "35", "--points", "random:6", "--thermal-effect",
                   "joint_offset:J2=0.01", cwd=tmp_path)
    assert r.returncode == 0 and "note:" not in r.stdout, r.stdout + r.stderr


def test_a_bad_time_is_a_path_line_error(tmp_path):
    path = tmp_path / "wu.csv"
    rows = ["point,j1,j2,j3,j4,j5,j6,x,y,z,t_min"]
    rows += [f"P{i},0,{i},0,0,30,0,500,0,{400 + i},{10 * i}" for i in range(1, 8)]
    rows[4] = rows[4].rsplit(",", 1)[0] + ",-5"
    path.write_text("\n".join(rows) + "\n")
    r = _rapidcomp("discover", path, "--tool", "0,0,150", cwd=tmp_path)
    assert r.returncode == 2 and "wu.csv:5" in r.stderr and "t_min is -5" in r.stderr


def test_temperature_columns_are_read_and_judged_against_time(tmp_path):
    """A sensor that follows the warm-up explains it as well as time (and
    its cold and warm readings are what fix --temperature needs); one that
    lags (its own 90 min) explains it worse and is not suggested."""
    path = _campaign(tmp_path, "ws.csv", "--tau-heat", "35",
                     "--thermal-effect", "joint_displacement:J2=0.03,0,0.04",
                     "--sensor", "temp_j2:22:47", "--sensor", "temp_lag:22:40:90")
    d = _discover(path)
    j2, lag = d.warmup.sensors
    assert (j2.name, lag.name) == ("temp_j2", "temp_lag")
    assert j2.t_cold == pytest.approx(22, abs=0.2) and j2.t_warm == pytest.approx(47, abs=0.5)
    assert "as well as time" in j2.text and "worse than time" in lag.text
    assert lag.tau_min == pytest.approx(90, rel=0.15) and d.warmup.state_from is None
    r = _rapidcomp("discover", path, "--tool", "0,0,150", "--out-profile", "p.csv", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    text = (tmp_path / "p.csv").read_text()
    assert "--temperature SIGNAL:22.0:47.0" in text and "temp_lag" not in text


def test_the_state_comes_from_a_temperature_the_points_follow_better():
    """Hand-made: the points follow a sensor whose warm-up has two time
    constants (no single exponential fits it): that column gives s."""
    rng = np.random.default_rng(5)
    times = np.array([0, 5, 10, 20, 30, 45, 60, 90, 120, 180, 240.0])
    T = 20 + 15 * (1 - np.exp(-times / 8)) + 10 * (1 - np.exp(-times / 120))
    q = np.array([[0, 10, 20, 0, 30, 0], [40, 0, 10, 5, 60, 0], [-30, 20, 0, 0, 45, 0],
                  [10, -20, 30, 60, 20, 90]], float)
    b = np.array([[0.05, -0.02, 0.08], [0.1, 0.0, -0.04], [0.0, 0.06, 0.02], [0.03, 0.03, 0.0]])
    rows_t = np.repeat(times, 4)
    rows_T = np.repeat(T, 4)
    xyz = 400 + ((rows_T - 20) / 25)[:, None] * np.tile(b, (len(times), 1)) \
        + rng.normal(0, 0.001, (len(rows_t), 3))
    w = estimate(np.tile(q, (len(times), 1)), xyz, rows_t, temperatures=(("temp_m", rows_T),))
    assert w.state_from == "temp_m" and "better than time" in w.sensors[0].text
    s = w.states(rows_t, (("temp_m", rows_T),))
    assert s.min() == pytest.approx(0, abs=1e-9) and s.max() == pytest.approx(1, abs=1e-9)


def test_simulate_needs_three_times(tmp_path):
    r = _rapidcomp("simulate", "-o", "two.csv", "--times", "0,60", "--tau-heat", "30",
                   cwd=tmp_path)
    assert r.returncode == 2 and "3 or more times" in r.stderr


def test_a_campaign_with_a_stop_gives_both_time_constants(tmp_path):
    """90 min of running, a 30 min stop, 90 min more (tau 35 heating, 70
    cooling): both found within 15 %, the profile carries both and fix
    --transient takes them; each effect's stated error holds the time
    constants' uncertainty (estimated from the same data: an amplitude
    tracks its tau), the truth within 2.5 errors of every value (with the
    taus held, dz of the thermal J2 displacement was 2.7 errors off)."""
    path = _campaign(tmp_path, "stop.csv", "--tau-heat", "35", "--tau-cool", "70",
                     "--thermal-effect", "joint_displacement:J2=0.03,0,0.04",
                     "--effect", "joint_offset:J3=0.01",
                     times="0,10,20,35,50,70,90,+30,90,100,115,140,180")
    text = path.read_text()
    assert "stood_min" in next(x for x in text.splitlines() if x.startswith("point,"))
    r = _rapidcomp("discover", path, "--tool", "0,0,150", "--json", "d.json",
                   "--out-profile", "p.csv", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "d.json").read_text())
    assert doc["tau_min"] == pytest.approx(35, rel=0.15)
    assert doc["tau_cool_min"] == pytest.approx(70, rel=0.15)
    # (Its interval holds the truth, and is no wider than the stop tells.)
    low, high = doc["tau_cool_interval_min"]
    assert low <= 70 <= high and high < 3 * low
    assert "measure longer stops" not in r.stdout
    true = {"joint_displacement:J2": {"dx_mm": 0.03, "dy_mm": 0.0, "dz_mm": 0.04},
            "joint_offset:J3": {"offset_deg": 0.01}}
    assert {s["effect"] for s in doc["steps"]} == set(true)
    for s in doc["steps"]:
        for k, v in s["params"].items():
            assert abs(v - true[s["effect"]][k]) < 2.5 * s["stderr"][k], (s["effect"], k)
    prof = read_profile(tmp_path / "p.csv")
    assert prof.tau_cool_min == pytest.approx(doc["tau_cool_min"], rel=1e-3)
    fixed = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", "p.csv", "--transient",
                       "--limit", "J5=-120:120", "-o", "c.mod", cwd=tmp_path)
    assert fixed.returncode == 0, fixed.stderr
    assert f"cooling tau {prof.tau_cool_min:g} min" in fixed.stdout


def test_a_campaign_without_noise_finds_its_effect_at_once(tmp_path):
    """simulate --noise 0: the scatter about each pose's curve is ~1e-9 mm;
    tested against it, 17 steps of rounding errors were named (and a 72-pose
    campaign ran for minutes). Against the least noise an instrument has,
    the one thermal effect is named and the data are explained."""
    path = tmp_path / "wu.csv"
    r = _rapidcomp("simulate", "-o", path, "--points", "random:12", "--tool", "0,0,150",
                   "--seed", "4",
                   "--times", "0,10,20", "--tau-heat", "30", "--noise", "0",
                   "--thermal-effect", "joint_displacement:J2=0.02,0,0.03", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    d = _discover(path)
    assert [s.effect.id for s in d.steps] == ["thermal:joint_displacement:J2"]
    assert d.verdict == "explained" and d.sigma_source.startswith("taken as 0.1 um")



def test_a_campaign_of_more_rows_than_a_file_holds_is_refused(tmp_path):
    """Rounds x points is bounded as random:N is (5000 rounds of 72 took
    three minutes and 1.8 GB): exit 2, nothing written."""
    times = ",".join(str(t) for t in range(0, 2000, 1))
    r = _rapidcomp("simulate", "-o", tmp_path / "m.csv", "--points", "random:100", "--times",
                   times, "--tau-heat", "45", cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert "2000 rounds of 100 points make 200000 rows; a campaign file holds at most 100000" \
        in r.stderr
    assert not (tmp_path / "m.csv").exists()


@pytest.mark.parametrize("sensor", ["temp_x:-300:-280", "temp_x:22:-280"])
def test_a_sensor_that_is_no_temperature_is_refused(tmp_path, sensor):
    """Below absolute zero: no campaign measures that; exit 2, nothing
    written (a flat sensor, the room's, is one)."""
    r = _rapidcomp("simulate", "-o", tmp_path / "m.csv", "--times", "0,10,20", "--tau-heat",
                   "30", "--sensor", sensor, cwd=tmp_path)
    assert r.returncode == 2 and f"--sensor {sensor}: expected temperatures" in r.stderr
    assert not (tmp_path / "m.csv").exists()


@pytest.mark.parametrize("sensors, says", [
    (("temp_m:20:40", "temp_m:20:40"), "--sensor temp_m:20:40: temp_m is given twice"),
    (("temp_m:20:40", "TEMP_M:20:45"), "--sensor TEMP_M:20:45: temp_m is given twice"),
    (("temp_:20:40",), "--sensor temp_:20:40: expected temp_NAME (letters, digits, '_')"),
    (("temp_a,b:20:40",), "--sensor temp_a,b:20:40: expected temp_NAME"),
])
def test_a_sensor_whose_column_cannot_be_read_back_is_refused(tmp_path, sensors, says):
    """One column per sensor, named temp_NAME: two of one name (which
    discover then refused: a column named twice), or no name, exit 2 here,
    nothing written."""
    args = [a for s in sensors for a in ("--sensor", s)]
    r = _rapidcomp("simulate", "-o", tmp_path / "m.csv", "--times", "0,10,20", "--tau-heat",
                   "30", *args, cwd=tmp_path)
    assert r.returncode == 2 and says in r.stderr, r.stderr
    assert not (tmp_path / "m.csv").exists()


def test_a_bad_thermal_effect_is_named_by_its_own_option(tmp_path):
    """--thermal-effect's values are checked as --effect's, and the message
    names the option given (it said --effect)."""
    r = _rapidcomp("simulate", "-o", tmp_path / "m.csv", "--times", "0,10,20", "--tau-heat",
                   "30", "--thermal-effect", "joint_offset:J2=nan", cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert "--thermal-effect joint_offset:J2=nan: joint_offset:J2 takes 1 number(s)" in r.stderr
    assert "--effect joint_offset" not in r.stderr
    assert not (tmp_path / "m.csv").exists()


def test_a_pose_beyond_the_limits_is_one_note_for_all_its_rounds():
    """A pose measured in every round of a campaign, past the model's joint
    limits, is said once with how many rounds (a new user read seven notes
    of S21); another pose of the same out-of-limit joint value is its own."""
    from types import SimpleNamespace

    from rapidcomp.discover.job import _beyond_limits
    robot = irb140()
    past = [0.0, 0.0, 0.0, 0.0, robot.upper_deg[4] + 1.0, 0.0]
    other = [10.0, 0.0, 0.0, 0.0, robot.upper_deg[4] + 1.0, 0.0]
    data = SimpleNamespace(names=[f"S21_t{t}" for t in (0, 20, 40)] + ["P1_t0", "P2_t0"],
                           q_deg=np.array([past] * 3 + [other, [0.0] * 6]))
    j5 = f"J5 {robot.upper_deg[4] + 1.0:g}"
    assert _beyond_limits(data, robot) == [
        f"points S21_t0, S21_t20 and 1 more (the same joints): {j5} beyond the model's joint "
        "limits",
        f"point P1_t0: {j5} beyond the model's joint limits"]


def test_a_campaign_that_leaves_an_effect_open_names_no_value(tmp_path):
    """Three rounds with a stop (0, 60, a 30 min stop, 120) of 12 poses: the
    heating and cooling time constants and the size of a thermal J2 shift
    trade off, and the fit's stated error is some 1e5 mm, beyond anything a
    robot has. discover does not call that explained, says which effect the
    data leave open and why, and writes no profile of it. A J2 shift over
    ten rounds of 30 poses is explained, its value within its error of the
    truth, and written."""
    path = _campaign(tmp_path, "open.csv", "--tau-heat", "30",
                     "--thermal-effect", "joint_displacement:J2=0,0,0.05",
                     points="random:12", times="0,60,+30,120")
    r = _rapidcomp("discover", path, "--tool", "0,0,150", "--out-profile", "open_prof.csv",
                   "--json", "open.json", "--report", "open.md", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "open.json").read_text())
    assert doc["verdict"] == "unexplained"
    open_steps = [s for s in doc["steps"] if not s["determined"]]
    assert open_steps and all(s["thermal"] for s in open_steps)
    # (What "beyond anything a robot has" means: an error above the 5 mm
    # a joint displacement may have, plausible.py.)
    assert all(max(map(abs, s["stderr"].values())) > 5 for s in open_steps)
    verdict = next(line for line in r.stdout.splitlines() if line.startswith("verdict:"))
    assert "do not determine thermal:joint_displacement" in verdict
    assert "over the 3 times of this warm-up campaign" in verdict
    # (What to measure: as the warm-up line advises, its tau poorly known.)
    tau_line = next(line for line in r.stdout.splitlines() if line.startswith("warm-up time"))
    assert "measure more often at the start" in tau_line
    # (The cooling time constant of one 30 min stop: its interval open.)
    assert "the stops tell the cooling time constant poorly: measure longer stops" in tau_line
    assert verdict.endswith("Measure longer stops and measure more often at the start.")
    # (Both ends at the search's edges, 1 and 1e4 min: said as open.)
    assert doc["tau_cool_interval_min"] == [None, None]
    assert "cooling time constant" in tau_line and "(95% interval any time constant searched" \
        in tau_line.split("cooling time constant")[1]
    assert "open_prof.csv not written: these data do not determine" in r.stdout
    # (The report and the JSON say the console's notes too.)
    assert any(n.startswith("open_prof.csv not written") for n in doc["notes"])
    assert "- open_prof.csv not written: these data do not determine" in \
        (tmp_path / "open.md").read_text()
    # The report's final model states the same errors as the JSON and the
    # summary (the time constants' uncertainty in them).
    table = (tmp_path / "open.md").read_text().split("## Final model")[1].split("##")[0]
    for s in open_steps:
        for k, err in s["stderr"].items():
            row = next(line for line in table.splitlines() if f"| {k} |" in line)
            assert float(row.split("|")[-2]) == pytest.approx(err, rel=0.01)
    assert not (tmp_path / "open_prof.csv").exists()

    path = _campaign(tmp_path, "long.csv", "--tau-heat", "30",
                     "--thermal-effect", "joint_displacement:J2=0.03,0,0.04")
    r = _rapidcomp("discover", path, "--tool", "0,0,150", "--out-profile", "long_prof.csv",
                   "--json", "long.json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "long.json").read_text())
    assert doc["verdict"] == "explained"
    step, = doc["steps"]
    assert step["determined"] and step["effect"] == "joint_displacement:J2"
    for axis, truth in (("dx_mm", 0.03), ("dz_mm", 0.04)):
        assert abs(step["params"][axis] - truth) < 3 * step["stderr"][axis] + 1e-3
    assert (tmp_path / "long_prof.csv").exists()
