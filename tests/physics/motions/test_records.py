"""Motion suites: a user's folder of records (with or without a manifest), one record file, the seven."""

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY, MotionError
from rlcontroller.physics.motions.records import (
    RECORDS_VARIABLE,
    SYNTHETIC_LABEL,
    choose_motions,
    load_records,
)

HEADER = "PEER NGA STRONG MOTION DATABASE RECORD\n{title}\nACCELERATION TIME SERIES IN UNITS OF G\n"


def write_at2(path: Path, acceleration_g: np.ndarray, dt: float, title: str = "Test event, station") -> Path:
    """A PEER NGA-West2 .AT2 file, five values a line."""
    lines = [f"NPTS= {acceleration_g.size:7d}, DT= {dt:.4f} SEC"]
    lines += [
        "  ".join(f"{v: .7E}" for v in acceleration_g[i : i + 5]) for i in range(0, acceleration_g.size, 5)
    ]
    path.write_text(HEADER.format(title=title) + "\n".join(lines) + "\n")
    return path


def write_csv(path: Path, acceleration_ms2: np.ndarray, dt: float) -> Path:
    rows = [f"{k * dt:.4f},{a:.6f}" for k, a in enumerate(acceleration_ms2)]
    path.write_text("time,acceleration [m/s2]\n" + "\n".join(rows) + "\n")
    return path


def pulse(count: int, pga: float, seed: int) -> np.ndarray:
    """A decaying random shake with the given peak."""
    rng = np.random.default_rng(seed)
    values = rng.standard_normal(count) * np.exp(-np.linspace(0.0, 4.0, count))
    return values * pga / np.max(np.abs(values))


@pytest.fixture
def my_records(tmp_path) -> Path:
    """A user's folder: two .AT2 records, one .csv record and a note that is not a record."""
    folder = tmp_path / "my records"
    folder.mkdir()
    write_at2(folder / "b_station.AT2", pulse(800, 0.30, 1), 0.01)
    write_at2(folder / "a_station.at2", pulse(1500, 0.05, 2), 0.005)
    write_csv(folder / "c_array.csv", pulse(400, 2.0, 3), 0.02)
    (folder / "notes.txt").write_text("downloaded on Monday\n")
    return folder


def test_a_folder_without_manifest_takes_every_at2_and_csv_file_in_name_order(my_records):
    motions, label = load_records(my_records)
    assert [m.name for m in motions] == ["a_station", "b_station", "c_array"]
    assert motions[0].dt == 0.005 and motions[1].pga == pytest.approx(0.30 * STANDARD_GRAVITY, rel=1e-6)
    assert motions[2].pga == pytest.approx(2.0, rel=1e-6)  # CSV in m/s^2, not g
    assert label == f"3 records from {my_records}, as recorded"


def test_a_manifest_chooses_orders_and_describes_the_records(my_records):
    (my_records / "manifest.csv").write_text(
        "file,event,year,station,component\nc_array.csv,Test Quake,2001,Array "
        "7,EW\nb_station.AT2,Other,1999,B,N\n"
    )
    motions, label = load_records(my_records)
    assert [m.name for m in motions] == ["c_array", "b_station"]
    assert motions[0].description == "Test Quake, 2001, Array 7, EW"
    assert label.startswith("2 records from")


def test_a_manifest_naming_missing_files_lists_them_and_where_to_look(my_records):
    (my_records / "manifest.csv").write_text("file,rsn\nb_station.AT2,1\ngone.AT2,42\n")
    with pytest.raises(MotionError) as error:
        load_records(my_records)
    message = str(error.value)
    assert "1 of 2 records of manifest.csv missing: gone.AT2" in message and "RSN 42" in message
    assert f"${RECORDS_VARIABLE}" in message and "\n" not in message


def test_a_manifest_without_a_file_column_is_refused(my_records):
    (my_records / "manifest.csv").write_text("record,event\nb_station.AT2,x\n")
    with pytest.raises(MotionError, match=r"manifest.csv:1: expected a 'file' column"):
        load_records(my_records)


def test_one_record_file(my_records):
    motions, label = load_records(my_records / "b_station.AT2", scale_pga_g=0.5)
    assert len(motions) == 1 and motions[0].pga == pytest.approx(0.5 * STANDARD_GRAVITY)
    assert label == f"record {my_records / 'b_station.AT2'}, scaled to PGA 0.5 g"


def test_an_empty_folder_and_a_missing_path_say_what_is_expected(tmp_path):
    with pytest.raises(MotionError, match=r"no records: expected .AT2 or .csv files"):
        load_records(tmp_path)
    with pytest.raises(MotionError, match=r"nowhere: no such file or folder"):
        load_records(tmp_path / "nowhere")


def test_the_seven_records_with_their_manifest(records):
    motions, label = load_records(records)
    assert len(motions) == 7 and label.startswith("7 records from") and label.endswith(", as recorded")
    sylmar = next(m for m in motions if m.name == "RSN1086_NORTHR_SYL090")
    assert sylmar.description == "Northridge-01, 1994, Sylmar - Olive View Med FF, 90"
    scaled, _ = load_records(records, scale_pga_g=0.3)
    assert all(m.pga == pytest.approx(0.3 * STANDARD_GRAVITY) for m in scaled)


def test_six_of_the_seven_missing_are_listed_with_where_to_get_them(records, tmp_path):
    shutil.copy(records / "manifest.csv", tmp_path)
    shutil.copy(records / "RSN1086_NORTHR_SYL090.AT2", tmp_path)
    with pytest.raises(MotionError) as error:
        load_records(tmp_path)
    message = str(error.value)
    assert "6 of 7 records of manifest.csv missing" in message and "RSN1106_KOBE_KJM000.AT2" in message
    assert "RSN1086_NORTHR" not in message.split("missing:")[1].split(";")[0]
    assert "ngawest2.berkeley.edu" in message and "\n" not in message


def test_without_records_the_suite_is_synthetic_and_labelled(monkeypatch):
    monkeypatch.delenv(RECORDS_VARIABLE, raising=False)
    motions, label = choose_motions(None)
    assert label == SYNTHETIC_LABEL and len(motions) == 7 and all(m.synthetic for m in motions)
    again, _ = choose_motions(None)
    np.testing.assert_array_equal(motions[3].acceleration, again[3].acceleration)


def test_records_variable_names_the_folder(my_records, monkeypatch):
    monkeypatch.setenv(RECORDS_VARIABLE, str(my_records))
    _, label = choose_motions(None)
    assert label.startswith("3 records from")


@pytest.mark.slow
def test_rlc_compares_on_a_users_folder_and_on_one_file(my_records, tmp_path):
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["compare", "lqg", "--records", str(my_records), "--out", str(out)])
    assert result.exit_code == 0, result.output
    metrics = pd.read_csv(out / "metrics.csv")
    assert set(metrics["record"]) == {"a_station", "b_station", "c_array"}
    assert set(metrics["suite"]) == {f"3 records from {my_records}, as recorded"}
    single = CliRunner().invoke(
        app, ["compare", "lqg", "--records", str(my_records / "c_array.csv"), "--out", str(tmp_path / "one")]
    )
    assert single.exit_code == 0, single.output
    assert set(pd.read_csv(tmp_path / "one" / "metrics.csv")["record"]) == {"c_array"}


@pytest.mark.slow
def test_rlc_evaluate_on_a_users_folder(my_records, tmp_path):
    """The committed policy on the user's records; the summary names the model it evaluated."""
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["evaluate", "--records", str(my_records), "--out", str(out)])
    assert result.exit_code == 0, result.output
    summary = (out / "summary.md").read_text()
    assert "3 records from" in summary and "best_policy.yaml" in summary
    assert "Evaluated RL: " in summary
    assert np.isfinite(pd.read_csv(out / "metrics.csv")["value"]).all()
