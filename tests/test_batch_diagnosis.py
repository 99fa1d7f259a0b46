"""diagnose_many / ``iwan-element diagnose a.csv b.csv --jobs N``: a campaign in one call, the
same answers as record by record, refusals kept as rows, one table and one JSON per run, and a
progress bar when asked."""

import json

import numpy as np
import pytest
from _diagnosis_cases import P, record

from iwan_element import IwanJoint, diagnose, diagnose_many
from iwan_element.diagnose import simulate_element_test


def _clean(seed, amps=(0.3, 0.8)):
    d = simulate_element_test(IwanJoint(P), np.array(amps) * P.phi_max, force_noise=5.0, seed=seed)
    return d.t, d.u, d.F


def test_microslip_only_record_does_not_claim_fs_and_beta():
    """Below macroslip the loops depend on KT, chi and R only (docs/equations.md section 2): the
    diagnosis' Jacobian has a degenerate direction in (Fs, beta), so both get no standard
    error and are not identified (a pseudo-inverse alone claimed Fs to 3e-7 %), while KT and
    chi are; with a record into macroslip all four are identified."""
    g = diagnose(*_clean(10))
    f = g.fit
    assert not f.identified["Fs"] and not f.identified["beta"] and not g.success
    assert np.isnan(f.stderr["Fs"]) and np.isnan(f.stderr["beta"])
    assert f.identified["KT"] and f.identified["chi"]
    assert any("Fs is not determined by the data" in w for w in f.warnings)
    g = diagnose(*_clean(10, (0.3, 0.8, 2.0)))
    assert g.success and all(g.fit.identified.values()), g.fit.report()


def test_batch_equals_record_by_record_and_keeps_refusals():
    hidden = record("backlash", 8.0, "ladder", 3)
    recs = [
        (hidden.t, hidden.u, hidden.F),
        _clean(1),
        (np.arange(10.0), np.zeros(10), np.zeros(10)),
    ]  # refused: too short
    before = [tuple(np.array(a, copy=True) for a in r) for r in recs]
    b = diagnose_many(recs, names=["gap", "clean", "short"], executor="serial", seed=0)
    for r, r0 in zip(recs, before):  # nothing mutated
        assert all(np.array_equal(x, y) for x, y in zip(r, r0))
    rows = {r["record"]: r for r in b.rows}
    assert rows["short"]["status"].startswith("refused:") and b.diagnoses[2] is None
    assert not b.success and any("not diagnosed" in w for w in b.warnings)
    for i, name in enumerate(("gap", "clean")):
        alone = diagnose(*recs[i])
        # the status is the diagnosis's verdict, never "ok" beside success False
        assert rows[name]["status"] == ("usable" if alone.success else "NOT usable")
        assert rows[name]["success"] == alone.success
        assert rows[name]["named"] == (" + ".join(alone.effects) or "none")
        assert rows[name]["error_after"] == pytest.approx(alone.error_after, rel=1e-12)
        assert b.diagnoses[i]["effects"] == list(alone.effects)
    assert "backlash" in rows["gap"]["named"] and rows["clean"]["named"] == "none"
    # the band misfit is measured where |F| < 0.25 max|F|, independently of the table code
    F, Fb = np.array(alone.F), np.array(alone.force_before)
    band = np.abs(F) < 0.25 * np.abs(F).max()
    assert rows["clean"]["band_before"] == pytest.approx(np.sqrt(np.mean((F - Fb)[band] ** 2)))
    text = b.report()
    assert "gap" in text and "refused" in text
    json.dumps(b.to_dict(), allow_nan=False)


def test_batch_on_processes_gives_the_serial_answer():
    recs = [_clean(2), _clean(3)]
    serial = diagnose_many(recs, executor="serial")
    procs = diagnose_many(recs)
    assert "processes" in procs.executor
    for a, c in zip(serial.rows, procs.rows):
        assert a["named"] == c["named"] and a["error_after"] == c["error_after"]


def test_bad_batch_input_is_named():
    good = _clean(4)
    with pytest.raises(ValueError, match="records"):
        diagnose_many([])
    with pytest.raises(ValueError, match=r"records\[0\]"):
        diagnose_many([(good[0], good[1])])
    with pytest.raises(ValueError, match="names"):
        diagnose_many([good], names=["a", "b"])
    with pytest.raises(ValueError, match="lowpas"):
        diagnose_many([good], lowpas=20.0)
    with pytest.raises(ValueError, match="band"):
        diagnose_many([good], band=1.5)


def test_cli_diagnoses_several_records_with_one_table_and_json(tmp_path, capsys):
    from iwan_element.cli import main

    paths = []
    for k in range(2):
        t, u, F = _clean(10 + k, (0.3, 0.8, 2.0))  # into macroslip: a success
        p = tmp_path / f"rec{k}.csv"
        p.write_text(
            "time [s],displacement [mm],force [kN]\n"
            + "\n".join(f"{a:.6f},{b:.8f},{c:.7f}" for a, b, c in zip(t, u * 1e3, F * 1e-3))
            + "\n"
        )
        paths.append(str(p))
    js, tab = tmp_path / "run.json", tmp_path / "run.csv"
    code = main(
        [
            "diagnose",
            *paths,
            "--units",
            "mm,kN",
            "--jobs",
            "1",
            "--json",
            str(js),
            "--table",
            str(tab),
        ]
    )
    out = capsys.readouterr().out
    assert code == 0, out
    assert "rec0.csv" in out and "rec1.csv" in out
    doc = json.loads(js.read_text())
    assert [r["record"] for r in doc["rows"]] == ["rec0.csv", "rec1.csv"]
    lines = tab.read_text().splitlines()
    assert lines[0].startswith("record,samples,named") and len(lines) == 3
    # every number under a heading with its unit, the NRMSE in % as the heading says
    head = lines[0].split(",")
    assert "NRMSE before [%]" in head and "misfit band before [N]" in head
    cell = dict(zip(head, lines[1].split(",")))
    assert float(cell["NRMSE before [%]"]) == pytest.approx(
        100 * doc["rows"][0]["error_before"], rel=1e-12
    )
    assert cell["status"] == ("usable" if doc["rows"][0]["success"] else "NOT usable")
    assert main(["diagnose", *paths, "--units", "mm,kN", "--plot", str(tmp_path / "x.png")]) == 1


def test_progress_bar_when_asked(capsys, monkeypatch):
    pytest.importorskip("tqdm")
    monkeypatch.delenv("CI", raising=False)  # bars are silent under CI
    t, u, F = _clean(5)
    quiet = diagnose(t, u, F)
    assert capsys.readouterr().err == ""
    loud = diagnose(t, u, F, progress=True)
    err = capsys.readouterr().err
    assert "diagnose" in err and "fit" in err
    assert loud.effects == quiet.effects and loud.error_after == quiet.error_after
    with pytest.raises(ValueError, match="progress"):
        diagnose(t, u, F, progress="yes")
