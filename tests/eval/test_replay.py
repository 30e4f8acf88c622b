"""`sortbot replay`: summary table, drawn frames + contact sheet, video; clear errors on bad files."""

from sortbot.cli import main


def test_replay_table_frames_and_video(collected, tmp_path, capsys):
    out, _ = collected
    mcap = out / "mcap" / "episode_000001.mcap"
    frames, video = tmp_path / "frames", tmp_path / "ep.mp4"
    assert main(["replay", str(mcap), "--frames", str(frames), "--video", str(video)]) == 0
    text = capsys.readouterr().out
    assert "actions" in text and "grasp" in text or "push" in text
    pngs = sorted(frames.glob("frame_*.png"))
    assert len(pngs) >= 2 and (frames / "contact_sheet.png").stat().st_size > 0
    assert video.stat().st_size > 1000


def test_replay_of_a_cut_file_shows_what_was_read(collected, tmp_path, capsys):
    out, _ = collected
    data = (out / "mcap" / "episode_000000.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.6)])
    assert main(["replay", str(cut)]) == 1
    captured = capsys.readouterr()
    assert "damaged" in captured.err and "step" in captured.out


def test_clear_errors_for_non_data(tmp_path, capsys):
    (tmp_path / "junk.mcap").write_text("hello")
    assert main(["replay", str(tmp_path / "junk.mcap")]) == 2
    assert main(["replay", str(tmp_path / "missing.mcap")]) == 2
    assert main(["datasets", "info", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(line.startswith("sortbot: error:") for line in err)
    assert "not a LeRobot dataset" in err[2]
