"""The start and end towers of a solve: the options, or asked for on a terminal like the lab program."""

from __future__ import annotations

import argparse

import pytest

from ur3hanoi.cli.options import UsageError
from ur3hanoi.cli.prompt import prompt_tower, towers


def test_prompt_repeats_like_the_lab_program(monkeypatch, capsys):
    answers = iter(["4", "x", "1", "3"])
    monkeypatch.setattr("builtins.input", lambda prompt: print(prompt, end="") or next(answers))
    assert prompt_tower("end", 3, exclude=0) == 2
    out = capsys.readouterr().out
    assert out.count("Enter the end tower <2 or 3> ") == 4
    assert out.count("Please just enter the character 2 or 3") == 3


def test_the_options_need_no_terminal(monkeypatch):
    monkeypatch.setattr("sys.stdin.isatty", lambda: False)
    assert towers(argparse.Namespace(start=3, end=1), 3, "", "solve") == (2, 0)
    with pytest.raises(UsageError, match=r"required when stdin is not a terminal \(towers 1..3\), e.g. ur3hanoi "
                                         r"ros-solve --start 1 --end 3"):
        towers(argparse.Namespace(start=1, end=None), 3, "", "ros-solve")


def test_the_missing_tower_is_asked_for(monkeypatch):
    monkeypatch.setattr("sys.stdin.isatty", lambda: True)
    monkeypatch.setattr("builtins.input", lambda prompt: "2")
    assert towers(argparse.Namespace(start=1, end=None), 3, "", "solve") == (0, 1)


def test_end_of_input_is_an_error(monkeypatch):
    def eof(prompt):
        raise EOFError

    monkeypatch.setattr("builtins.input", eof)
    with pytest.raises(UsageError, match="no start tower entered"):
        prompt_tower("start", 3)
