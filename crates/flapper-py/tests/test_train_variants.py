"""scripts/train-variants.py: each variant's config is the base with exactly its keys set, and a bad
variants file stops with the file, the line and what to write instead."""

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
spec = importlib.util.spec_from_file_location("train_variants", ROOT / "scripts" / "train-variants.py")
train_variants = importlib.util.module_from_spec(spec)
spec.loader.exec_module(train_variants)

BASE = """[runner]
envs = 256
threads = 0

[task.reward]
position_weight = 0.5
position_dive_gain = 2.0

[task.episode]
max_steps = 1500"""


def test_a_written_key_is_replaced_in_its_own_table_and_nothing_else_moves():
    text = train_variants.edited(BASE, [("task.reward", "position_dive_gain", "1.0"), ("runner", "threads", "2")])
    assert text == BASE.replace("position_dive_gain = 2.0", "position_dive_gain = 1.0").replace(
        "threads = 0", "threads = 2"
    )


def test_a_key_the_config_leaves_out_is_added_to_the_named_table():
    text = train_variants.edited(BASE, [("task.reward", "flap_rate_weight", "0.05")]).split("\n")
    reward, episode = text.index("[task.reward]"), text.index("[task.episode]")
    assert text.index("flap_rate_weight = 0.05") in range(reward + 1, episode)
    assert len(text) == len(BASE.split("\n")) + 1


def test_a_table_the_config_lacks_is_an_error_naming_it():
    with pytest.raises(ValueError, match=r"no \[task.rewards\] table"):
        train_variants.edited(BASE, [("task.rewards", "position_weight", "1.0")])


def test_a_key_that_only_starts_like_another_is_not_taken_for_it():
    base = "[task.reward]\nenergy_weight = 0.1\nenergy_weight_extra = 3"
    assert train_variants.edited(base, [("task.reward", "energy_weight", "0.2")]).split("\n")[1:] == [
        "energy_weight = 0.2",
        "energy_weight_extra = 3",
    ]


def test_the_variants_file_is_read_with_comments_and_blank_lines(tmp_path):
    path = tmp_path / "v.txt"
    path.write_text("# two variants\n\nhalf-dive  task.reward.position_dive_gain=1.0  # the dive x2\n"
                    "noise runner.init_from_noise_std=0.3 task.reward.flap_max_hz=5.75\n")
    assert train_variants.read_variants(path) == [
        ("half-dive", [("task.reward", "position_dive_gain", "1.0")]),
        ("noise", [("runner", "init_from_noise_std", "0.3"), ("task.reward", "flap_max_hz", "5.75")]),
    ]


@pytest.mark.parametrize(
    "line, says",
    [
        ("a position_dive_gain=1.0", r"line 2: 'position_dive_gain=1.0' is not table.key=value"),
        ("a task.reward.position_dive_gain", r"line 2: 'task.reward.position_dive_gain' is not table.key=value"),
        ("a task.reward.position_dive_gain=", r"is not table.key=value"),
        ("a", r"line 2: variant 'a' changes nothing"),
        ("first runner.envs=8", r"line 2: 'first' is not a new variant name"),
        ("a/b runner.envs=8", r"line 2: 'a/b' is not a new variant name"),
    ],
)
def test_a_bad_line_stops_with_its_file_and_number(tmp_path, capsys, line, says):
    path = tmp_path / "v.txt"
    path.write_text(f"first runner.envs=16\n{line}\n")
    with pytest.raises(SystemExit) as stop:
        train_variants.read_variants(path)
    assert stop.value.code == 2
    message = capsys.readouterr().err
    assert message.startswith(f"error: {path}, ") and message.count("\n") == 1
    assert re.search(says, message), message


def test_an_empty_variants_file_is_refused(tmp_path, capsys):
    path = tmp_path / "v.txt"
    path.write_text("# nothing yet\n")
    with pytest.raises(SystemExit):
        train_variants.read_variants(path)
    assert "holds no variant" in capsys.readouterr().err
