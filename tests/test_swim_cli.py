"""``depthtrack swim``: bad input, and a small thesis-style evaluation on the CMU back-stroke take."""
import json

import pytest

from depthtrack.cli import main


def one_line_error(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_missing_bvh_exits_2_with_one_line(tmp_path, capsys):
    missing = tmp_path / "nope.bvh"
    assert main(["swim", "evaluate", "--train", str(missing), "--test", str(missing)]) == 2
    line = one_line_error(capsys)
    assert line.startswith("depthtrack swim: ") and str(missing) in line and "no such BVH file" in line


def test_unknown_estimator_exits_2_with_one_line(shared_data, capsys):
    bvh = str(shared_data / "cmu" / "126_01.bvh")
    assert main(["swim", "evaluate", "--train", bvh, "--test", bvh, "--estimator", "median"]) == 2
    assert "unknown estimator median" in one_line_error(capsys)
    assert main(["swim", "evaluate", "--train", bvh, "--test", bvh, "--particles", "ten"]) == 2
    assert "--particles" in one_line_error(capsys)


def test_malformed_bvh_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n")
    assert main(["swim", "train", str(bad), "-o", str(tmp_path / "m.json")]) == 2
    assert str(bad) in one_line_error(capsys)
    assert not (tmp_path / "m.json").exists()


def test_small_evaluation_on_cmu_back_stroke(shared_data, tmp_path, capsys):
    bvh = str(shared_data / "cmu" / "126_01.bvh")
    report = tmp_path / "report"
    code = main(["swim", "evaluate", "--train", bvh, "--test", bvh, "--particles", "2000", "--sigma", "0.1",
                 "--frames", "40", "--init", "truth", "--estimator", "map,kmeans", "--json",
                 "--thesis-model-particles", "0", "--report", str(report), "--seed", "1"])
    assert code == 0
    metrics = json.loads(capsys.readouterr().out)
    window = metrics["test_window"]
    # never train on the test window
    assert all(c["end_frame"] <= window["first_frame"] for c in metrics["training_cycles"])
    assert len(metrics["training_cycles"]) >= 4 and window["frames"] == 40
    # measurements alone: 26 angles with 0.05 rad noise -> about 26 * 0.0025
    assert metrics["baseline_measurement"]["error"] == pytest.approx(0.065, rel=0.25)
    pf = next(r for r in metrics["runs"] if r["filter"] == "particle")
    ukf = next(r for r in metrics["runs"] if r["filter"] == "ukf")
    assert set(pf["estimators"]) == {"map", "kmeans"}
    # measured: PF 2000 particles ~0.6-1.4 rad^2 (12 cm), UKF ~0.03 rad^2 (1.7 cm)
    assert pf["estimators"]["map"]["error"] < 3.0
    assert pf["estimators"]["map"]["joint_error_cm"] < 20.0
    assert ukf["estimators"]["mean"]["error"] < 0.1
    assert ukf["estimators"]["mean"]["joint_error_cm"] < 3.0
    assert pf["phase_error"] < 0.06 and ukf["phase_error"] < 0.03
    assert (report / "metrics.json").is_file() and (report / "results.md").is_file()
    assert (report / "fig7_9a_particles_map.png").is_file()


def test_derivatives_command_ranks_filters(shared_data, capsys):
    bvh = str(shared_data / "cmu" / "126_01.bvh")
    assert main(["swim", "derivatives", bvh, "--json"]) == 0
    rows = {r["name"]: r["error"] for r in json.loads(capsys.readouterr().out)}
    assert rows["D1 [1 -1]"] > 10 * max(rows["D2 1/2[1 0 -1]"], rows["Taylor r=2"], rows["Taylor r=3"])


def test_new_filters_and_gaps_in_the_json(shared_data, capsys):
    bvh = str(shared_data / "cmu" / "126_01.bvh")
    code = main(["swim", "evaluate", "--train", bvh, "--test", bvh, "--filter", "rbpf,ukf-tuned,smoother",
                 "--particles", "2000", "--frames", "60", "--init", "truth", "--gaps", "10", "--json",
                 "--thesis-model-particles", "0", "--seed", "1"])
    assert code == 0
    metrics = json.loads(capsys.readouterr().out)
    base = metrics["baseline_measurement"]["error"]
    assert metrics["measurement_noise_estimate"] == pytest.approx(0.05, rel=0.2)
    assert metrics["process_noise"]["residual_frames"] > 100
    runs = {r["filter"]: r for r in metrics["runs"]}
    assert set(runs) == {"rbpf", "ukf-tuned", "smoother"}
    # measured on this window: rbpf ~0.03, ukf-tuned ~0.03, smoother ~0.015 against 0.065
    for name in runs:
        assert runs[name]["estimators"]["mean"]["error"] < 0.75 * base, name
    (gaps,) = metrics["gaps"]
    assert gaps["length"] == 10 and gaps["gaps"][0] == [20, 30]
    methods = gaps["methods"]
    assert {"hold", "constant_velocity", "interpolation", "rbpf", "ukf-tuned", "smoother"} <= set(methods)
    assert all(len(m["inside_per_phase"]) == 4 for m in methods.values())
    # after a gap the filters pick up again: back below the measurements' own error
    assert methods["rbpf"]["after"] < base and methods["ukf-tuned"]["after"] < base
