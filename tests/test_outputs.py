import pytest

from pipefollow.files.output_paths import OutputError, check_output_file, first_missing, remove_empty_folders


def test_first_missing_and_removing_what_was_made(tmp_path):
    target = tmp_path / "a" / "b" / "c"
    assert first_missing(target) == tmp_path / "a"
    assert first_missing(tmp_path) is None
    made = first_missing(target)
    target.mkdir(parents=True)
    (tmp_path / "keep").mkdir()
    remove_empty_folders(target, made)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep"]


def test_removing_stops_at_a_folder_that_holds_something(tmp_path):
    target = tmp_path / "a" / "b"
    made = first_missing(target)
    target.mkdir(parents=True)
    (tmp_path / "a" / "result.csv").write_text("x")
    remove_empty_folders(target, made)
    assert not target.exists() and (tmp_path / "a" / "result.csv").exists()
    remove_empty_folders(tmp_path / "a", None)  # nothing was made: nothing goes
    assert (tmp_path / "a").exists()


def test_check_output_file(tmp_path):
    assert check_output_file(tmp_path / "x.PNG", "--plot", ("png", "svg")) == "png"
    (tmp_path / "dir.png").mkdir()
    with pytest.raises(OutputError, match="is a folder"):
        check_output_file(tmp_path / "dir.png", "--plot", ("png",))
    (tmp_path / "f").write_text("")
    with pytest.raises(OutputError, match=r"'.*f' is a file, not a folder"):
        check_output_file(tmp_path / "f" / "g" / "x.png", "--plot", ("png",))
