"""The progress CSV schema (chopperscape.learn.progress): what every learner writes and plot/seeds read; the plot
of progress CSVs (`python -m chopperscape.learn.plot`)."""

import math

import pytest

from chopperscape.learn import progress


def test_a_writer_writes_the_header_and_flushes_every_row(tmp_path):
    path = tmp_path / "deep" / "progress.csv"
    w = progress.Writer(path)
    assert path.read_text() == ",".join(progress.COLUMNS) + "\n"
    w.row({"env_steps": 10, "wall_s": "0.5", "episodes": 0, "entropy": "1.6"})
    # Flushed before close: a crashed run keeps its rows. Missing columns are blank.
    lines = path.read_text().splitlines()
    assert len(lines) == 2
    row = dict(zip(progress.COLUMNS, lines[1].split(",")))
    assert row["env_steps"] == "10" and row["entropy"] == "1.6" and row["mean_return"] == "" and row["bird"] == ""
    with pytest.raises(KeyError, match="entropyy"):
        w.row({"env_steps": 11, "entropyy": 1})
    assert len(path.read_text().splitlines()) == 2
    w.close()


def test_a_writer_refuses_columns_outside_the_schema(tmp_path):
    with pytest.raises(ValueError, match="must start with"):
        progress.Writer(tmp_path / "a.csv", ["wall_s", "env_steps"])
    with pytest.raises(ValueError, match="mean_reward"):
        progress.Writer(tmp_path / "b.csv", [*progress.RETURNS, "mean_reward"])
    assert not (tmp_path / "a.csv").exists() and not (tmp_path / "b.csv").exists()


def test_read_skips_rows_without_returns_and_names_bad_files(tmp_path):
    path = tmp_path / "p.csv"
    with progress.Writer(path) as w:
        w.row({"env_steps": 100, "wall_s": "1.0", "episodes": 0})
        w.row(
            {
                "env_steps": 200,
                "wall_s": "2.0",
                "episodes": 3,
                "mean_return": "50.5",
                "std_return": "1.0",
                "mean_length": "40.0",
                "ended": 3,
                "bird": "1.000",
            }
        )
    cols = progress.read(path, ("env_steps", "mean_return", "fuel", "bird"))
    assert cols["env_steps"] == [200.0] and cols["mean_return"] == [50.5] and cols["bird"] == [1.0]
    assert math.isnan(cols["fuel"][0])
    # The examples' files (the return columns only) read the same way.
    short = tmp_path / "short.csv"
    with progress.Writer(short, progress.RETURNS) as w:
        w.row(
            {"env_steps": 1, "wall_s": "0.1", "episodes": 1, "mean_return": "9", "std_return": "0", "mean_length": "9"}
        )
    assert progress.read(short)["mean_length"] == [9.0]
    with pytest.raises(ValueError, match="missing columns"):
        progress.read(short, ("entropy",))
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(ValueError, match=r"empty\.csv: no rows"):
        progress.read(tmp_path / "empty.csv")
    (tmp_path / "nothing.csv").write_text(
        ",".join(progress.COLUMNS) + "\n1,0.1,0" + "," * (len(progress.COLUMNS) - 3) + "\n"
    )
    with pytest.raises(ValueError, match="no finished episode"):
        progress.read(tmp_path / "nothing.csv")
    (tmp_path / "text.csv").write_text("env_steps,wall_s,episodes,mean_return,std_return,mean_length\nx,1,1,1,1,1\n")
    with pytest.raises(ValueError, match=r"text\.csv: not a progress CSV"):
        progress.read(tmp_path / "text.csv")


def test_the_schema_is_the_documented_contract():
    # The column names and their order are a file format others read (python/README.md, docs/learning.md): pinned here.
    assert progress.RETURNS == ("env_steps", "wall_s", "episodes", "mean_return", "std_return", "mean_length")
    assert progress.DIAGNOSTICS == (
        "learning_rate", "entropy", "approx_kl", "clip_frac", "explained_var", "value_loss", "policy_loss",
    )  # fmt: skip
    assert progress.ENDINGS == ("ended", "bird", "fuel", "limit")
    assert progress.GUIDANCE == ("aux_loss", "teacher_kl")
    assert progress.SELF_SUPERVISED == ("recon_loss",)
    assert progress.NOVELTY == ("rnd_loss", "novelty")
    assert progress.COLUMNS == (
        progress.RETURNS
        + progress.DIAGNOSTICS
        + progress.ENDINGS
        + progress.GUIDANCE
        + progress.SELF_SUPERVISED
        + progress.NOVELTY
    )
    assert progress.OLDER_HEADERS == (progress.OLDER_COLUMNS, progress.OLDER_COLUMNS + progress.SELF_SUPERVISED)


@pytest.mark.parametrize("version", range(2))
def test_a_csv_written_before_the_last_column_group_resumes_with_it_blank(tmp_path, version):
    """Run folders of earlier versions (no `recon_loss` column; no `rnd_loss` and `novelty`) resume: their rows are
    kept, the new columns blank; any other header is still refused."""
    header = progress.OLDER_HEADERS[version]
    older = tmp_path / "older.csv"
    row = ["8", "1.0", "2", "10.0", "1.0", "5.0"] + [""] * (len(header) - 6)
    older.write_text(",".join(header) + "\n" + ",".join(row) + "\n" + ",".join(["16", *row[1:]]) + "\n")
    progress.Writer.resume(older, 8).close()
    lines = older.read_text().splitlines()
    assert lines == [",".join(progress.COLUMNS), ",".join(row + [""] * (len(progress.COLUMNS) - len(header)))]
    other = tmp_path / "other.csv"
    other.write_text(",".join(progress.OLDER_COLUMNS[:-1]) + "\n")
    with pytest.raises(ValueError, match="its header differs"):
        progress.Writer.resume(other, 8)


def test_every_refusal_names_the_file_first(tmp_path):
    # Each message starts with what was wrong, so that a one-line error says which file (from the mutation pass).
    with pytest.raises(ValueError, match=r"^progress columns must start with \['env_steps'"):
        progress.Writer(tmp_path / "a.csv", ["wall_s"])
    w = progress.Writer(tmp_path / "w.csv")
    with pytest.raises(KeyError, match=r"^\"not progress columns: \['bogus'\]\"$"):
        w.row({"bogus": 1})
    w.close()
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(ValueError, match=rf"^{tmp_path / 'empty.csv'}: no rows$"):
        progress.read(tmp_path / "empty.csv")
    (tmp_path / "short.csv").write_text("env_steps,wall_s\n1,2\n")
    with pytest.raises(
        ValueError,
        match=rf"^{tmp_path / 'short.csv'}: missing columns .*expected {','.join(progress.RETURNS)}, \.\.\.\)$",
    ):
        progress.read(tmp_path / "short.csv")
    (tmp_path / "none.csv").write_text(",".join(progress.RETURNS) + "\n1,0.1,0,,,\n")
    with pytest.raises(ValueError, match=rf"^{tmp_path / 'none.csv'}: no finished episode yet$"):
        progress.read(tmp_path / "none.csv")
    (tmp_path / "text.csv").write_text(",".join(progress.RETURNS) + "\nx,1,1,1,1,1\n")
    with pytest.raises(ValueError, match=rf"^{tmp_path / 'text.csv'}: not a progress CSV \("):
        progress.read(tmp_path / "text.csv")


def test_a_writer_makes_missing_folders(tmp_path):
    with progress.Writer(tmp_path / "a" / "b" / "c" / "progress.csv") as w:
        w.row({"env_steps": 1})
    assert (tmp_path / "a" / "b" / "c" / "progress.csv").is_file()


def test_plot_draws_progress_csvs_and_names_a_bad_one(tmp_path, capsys, monkeypatch):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed")
    from chopperscape.learn import plot

    good = tmp_path / "run" / "progress.csv"
    good.parent.mkdir()
    good.write_text(
        "env_steps,wall_s,episodes,mean_return,std_return,mean_length\n1000,1.0,3,500,100,510\n2000,2.0,6,900,150,910\n"
    )
    out = tmp_path / "curve.png"
    assert plot.main([str(good), "--out", str(out), "--hline", "random=600"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = tmp_path / "bad.csv"
    bad.write_text("steps,return\n1,2\n")
    assert plot.main([str(bad), "--out", str(tmp_path / "x.png")]) == 2
    assert "missing columns" in capsys.readouterr().err and not (tmp_path / "x.png").exists()
    # --frame-skip: one per CSV; the left panel then counts game frames (env steps × frame skip).
    import matplotlib.axes

    drawn = []
    real_plot = matplotlib.axes.Axes.plot
    monkeypatch.setattr(
        matplotlib.axes.Axes, "plot", lambda ax, x, *r, **k: drawn.append(list(x)) or real_plot(ax, x, *r, **k)
    )
    assert plot.main([str(good), str(good), "--frame-skip", "1", "--frame-skip", "4", "--out", str(out)]) == 0
    assert drawn == [[0.001, 0.002], [1 / 60, 2 / 60], [0.004, 0.008], [1 / 60, 2 / 60]]
    for args, message in (
        (["--frame-skip", "4"], "1 --frame-skip for 2 CSV files"),
        (["--frame-skip", "0"] * 2, "allowed an integer ≥ 1"),
    ):
        with pytest.raises(SystemExit):
            plot.main([str(good), str(good), *args, "--out", str(tmp_path / "y.png")])
        assert message in capsys.readouterr().err and not (tmp_path / "y.png").exists()
