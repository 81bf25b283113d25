"""The `ur3hanoi solve` command: JSON outcome, exit 3 on a suction fault, the lab program's prompts.

(Kept apart from test_cli.py because every case here runs the MuJoCo simulator.)
"""

from __future__ import annotations

import json

import pytest

from ur3hanoi import cli

JSON_KEYS = {"status", "exit_code", "moves_completed", "moves_total", "error", "final_blocks", "suction_on_at_end",
             "at_home_at_end", "sim_time_s", "wall_time_s", "realtime_factor", "max_tracking_error_rad",
             "feedback_events"}


def test_cli_solve_json(capsys: pytest.CaptureFixture[str]) -> None:
    code = cli.main(["solve", "--start", "2", "--end", "3", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and set(out) >= JSON_KEYS and out["status"] == "solved" and out["error"] is None
    assert [(b["block"], b["tower"], b["height"]) for b in out["final_blocks"]] == [(1, 3, 1), (2, 3, 2), (3, 3, 3)]


def test_cli_solve_remove_block_json_exit_3(capsys: pytest.CaptureFixture[str]) -> None:
    code = cli.main(["solve", "--start", "1", "--end", "2", "--remove-block", "2", "--json"])
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert code == 3 and out["status"] == "halted" and out["exit_code"] == 3
    assert "block 2" in out["error"] and captured.err == f"ur3hanoi: error: {out['error']}\n"
    assert out["suction_on_at_end"] is False and out["at_home_at_end"] is True


def test_cli_solve_summary_on_a_fault_then_one_error_line(capsys: pytest.CaptureFixture[str]) -> None:
    code = cli.main(["solve", "--start", "1", "--end", "3", "--drop-during-move", "1"])
    captured = capsys.readouterr()
    assert code == 3 and captured.out.startswith("halted: 0/7 moves, tower 1 -> 3")
    assert captured.err.startswith("ur3hanoi: error: suction fault in move 1/7") and captured.err.count("\n") == 1


def test_cli_solve_without_terminal_needs_start_and_end(capsys: pytest.CaptureFixture[str],
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("sys.stdin.isatty", lambda: False, raising=False)
    assert cli.main(["solve"]) == 2
    assert "--start and --end are required" in capsys.readouterr().err


def test_cli_prompt_reprompts_on_bad_input(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    # Prompted towers, then --view without a display stops the run before planning (exit 2).
    answers = iter(["4", "x", "1", "1", "3"])
    prompts: list[str] = []

    def fake_input(prompt: str = "") -> str:
        prompts.append(prompt)
        return next(answers)

    monkeypatch.setattr("sys.stdin.isatty", lambda: True, raising=False)
    monkeypatch.setattr("builtins.input", fake_input)
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert cli.main(["solve", "--view"]) == 2
    captured = capsys.readouterr()
    assert captured.out.count("Please just enter") == 3
    assert prompts == ["Enter the start tower <1 2 or 3> "] * 3 + ["Enter the end tower <2 or 3> "] * 2
    assert "no display" in captured.err


def test_cli_view_without_display_exits_2(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert cli.main(["solve", "--start", "1", "--end", "3", "--view"]) == 2
    err = capsys.readouterr().err
    assert "no display" in err and "use --video FILE.mp4 or --frames DIR" in err


def test_cli_rejects_bad_fault_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["solve", "--start", "1", "--end", "3", "--remove-block", "4"]) == 2
    assert cli.main(["solve", "--start", "1", "--end", "3", "--drop-during-move", "8"]) == 2
    assert cli.main(["solve", "--start", "1", "--end", "1"]) == 2
    err = capsys.readouterr().err
    assert "--remove-block 4 is invalid" in err and "--drop-during-move 8 is invalid" in err


@pytest.mark.parametrize(("option", "profile", "free_v"), [([], "lab_sim", 1.45),
                                                            (["--suction-profile", "real"], "real", 1.40)])
def test_cli_solve_reports_the_suction_profile_it_reads(capsys: pytest.CaptureFixture[str], option: list[str],
                                                        profile: str, free_v: float) -> None:
    """The JSON names the profile, and the halt message's AIN0 is that profile's cup-free level."""
    code = cli.main(["solve", "--start", "1", "--end", "2", "--remove-block", "3", "--json", *option])
    out = json.loads(capsys.readouterr().out)
    assert code == 3 and out["suction"]["profile"] == profile
    ain0 = float(out["error"].split("AIN0=")[1].split(" V")[0])
    assert abs(ain0 - free_v) < 0.1
