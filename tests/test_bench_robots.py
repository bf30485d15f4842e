"""benchmarks/bench_robots.py: its pure helpers always; one arm's scene when robosuite is installed (pip install --no-deps)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("bench_robots", ROOT / "benchmarks" / "bench_robots.py")
bench = importlib.util.module_from_spec(_spec)
sys.modules["bench_robots"] = bench            # its dataclasses look their module up
_spec.loader.exec_module(bench)


def test_trajectory_csv_has_the_header_and_one_row_per_sample(tmp_path):
    path = bench.write_trajectory(tmp_path / "t.csv", ["j1", "j2"], [(0.0, [0, 10]), (1.5, [-35.25, 12.5])])
    assert path.read_text().splitlines() == ["t,j1,j2", "0,0.000000,10.000000", "1.5,-35.250000,12.500000"]
    with pytest.raises(ValueError):
        bench.write_trajectory(tmp_path / "bad.csv", ["j1", "j2"], [(0.0, [0])])


def test_sampling_at_100_hz_passes_every_key_and_rests_there():
    keys = [(0.0, [0.0, 0.0]), (0.5, [10.0, -20.0]), (1.0, [10.0, -20.0]), (1.2, [0.0, 0.0])]
    rows = bench.sample(keys, 100.0)
    assert len(rows) == 121 and rows[0][0] == 0.0 and rows[-1][0] == pytest.approx(1.2)
    by_t = {round(t, 6): v for t, v in rows}
    for t, v in keys:
        assert by_t[round(t, 6)] == pytest.approx(v)
    # eased: the first step from a key moves far less than a straight line would
    assert abs(rows[1][1][0]) < 0.1 * (10.0 / 50)
    with pytest.raises(ValueError):
        bench.sample([(0.0, [0.0]), (0.0, [1.0])], 100.0)


def test_near_held_finds_the_nearest_end_or_clip_within_the_zone():
    held = [("start", 0.0), ("clip 1", 0.5), ("end", 1.2)]
    assert bench.near_held(0.53, held, 0.07) == ("clip 1", 0.5)
    assert bench.near_held(0.8, held, 0.07) is None
    assert bench.near_held(1.0, [], 0.07) is None


def test_second_opinion_reads_the_validations_disagreements_at_the_worst_step():
    """A contact event agrees unless its pair disagrees over an interval holding its worst step;
    a bend has no second opinion."""
    validation = {"disagreements": [{"type": "cable-structure", "a": "hose", "b": "link3", "t_start": 1.0,
                                     "t_end": 1.2, "reason": "between points"}]}
    event = {"type": "cable-structure", "a": "hose", "b": "link3", "t_worst": 1.1}
    assert bench.second_opinion(event, validation) == "MuJoCo differs there (between points)"
    assert bench.second_opinion({**event, "t_worst": 1.3}, validation) == "MuJoCo agrees at its worst step"
    assert bench.second_opinion({**event, "b": "link4"}, validation) == "MuJoCo agrees at its worst step"
    assert bench.second_opinion({**event, "type": "bend"}, validation) == "no contact: no second opinion"
    warned = ["cable 'hose': its least bend radius, 0.02639 m at t = 3 s, spans fewer than 3 of its elements "
              "(0.02915 m each): the simulated rod cannot resolve a bend that tight"]
    assert "cannot resolve" in bench.second_opinion({**event, "type": "bend", "a": "hose"}, validation, warned)
    assert bench.second_opinion({**event, "type": "bend", "a": "air"}, validation, warned) == \
        "no contact: no second opinion"
    assert bench.second_opinion(event, {}) == "not validated"


def test_ratio_of_the_report_timing():
    t = {"sim_s": 2.0, "check_s": 0.5, "validate_s": 0.3, "record_s": 0.2}
    assert bench.ratio(t) == pytest.approx(0.5)


def test_every_arm_programs_five_joints_within_the_program():
    for name, arm in bench.ZOO.items():
        assert len(arm.joints) == len(arm.home) == 5, name
    assert all(len(d) == 5 for _, d in bench.PROGRAM)
    assert 3.0 <= bench.PROGRAM[-1][0] <= 5.0


def test_missing_packages_are_explained_not_a_traceback(monkeypatch, capsys):
    monkeypatch.setattr(bench, "package_root", lambda package: None)
    assert bench.main(["--scenes-only"]) == 2
    err = capsys.readouterr().err
    assert "not installed: gymnasium-robotics, robosuite" in err and "pip install --no-deps robosuite gymnasium-robotics" in err
    assert "no arm of the zoo is installed" in err


@pytest.mark.skipif(bench.package_root("robosuite") is None, reason="robosuite (pip install --no-deps robosuite) is not installed")
def test_one_arm_scene_loads(tmp_path):
    arm = bench.ZOO["panda"]
    path, _, clear = bench.scene_for("panda", arm, bench.package_root(arm.package), tmp_path, None, None)
    assert clear > 0
    out = subprocess.run([sys.executable, "-c", "import sys; from cablecheck.cli.main import main; sys.exit(main())",
                          "check", str(path)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "valid scene 'zoo-panda'" in out.stdout
    csv = (tmp_path / "panda.csv").read_text().splitlines()
    assert csv[0] == "t," + ",".join(arm.joints) and len(csv) == len(bench.PROGRAM) + 1


@pytest.mark.skipif(bench.package_root("gymnasium_robotics") is None,
                    reason="gymnasium-robotics (pip install --no-deps gymnasium-robotics) is not installed")
@pytest.mark.parametrize("name", [n for n, a in bench.ZOO.items() if a.fragment is not None])
def test_a_fragment_arm_is_wrapped_and_its_scene_loads(tmp_path, name):
    """The include fragments (Fetch; the kitchen Franka, whose assets file sets
    its own relative meshdir and whose links carry a childclass limiting every
    joint) load on their own and as the benchmark's scene."""
    import mujoco

    arm = bench.ZOO[name]
    root = bench.package_root(arm.package)
    m = mujoco.MjModel.from_xml_path(str(bench.standalone(arm, root, tmp_path)))
    assert all(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j) >= 0 for j in arm.joints)
    path, _, _ = bench.scene_for(name, arm, root, tmp_path, None, None)
    out = subprocess.run([sys.executable, "-c", "import sys; from cablecheck.cli.main import main; sys.exit(main())",
                          "check", str(path)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr


def test_doc_section_is_replaced_between_its_markers_only(tmp_path):
    doc = tmp_path / "performance.md"
    doc.write_text("# P\n\n<!-- bench_startup -->\nstartup\n<!-- /bench_startup -->\n\n"
                   "<!-- bench_robots -->\nold zoo\n<!-- /bench_robots -->\nafter\n")
    bench.write_doc(doc, "new zoo")
    text = doc.read_text()
    assert "old zoo" not in text and "<!-- bench_robots -->\nnew zoo\n<!-- /bench_robots -->\nafter\n" in text
    assert "<!-- bench_startup -->\nstartup\n<!-- /bench_startup -->" in text
    import bench_startup
    assert (bench_startup.BEGIN, bench_startup.END) == ("<!-- bench_startup -->", "<!-- /bench_startup -->")
