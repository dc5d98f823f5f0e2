import json
from pathlib import Path

from seamless_usd_cli.main import main


def test_version_and_help_exit_zero(capsys):
    assert main(["--version"]) == 0
    assert "seamless-usd" in capsys.readouterr().out


def test_unknown_command_is_a_usage_error(capsys):
    assert main(["frobnicate"]) == 2
    assert "invalid choice" in capsys.readouterr().err


def test_options_refuse_what_the_command_line_would_when_they_are_made():
    """Every value the command line would refuse is a UsageError when the options are made (a mode it does not
    know, when the run starts, before any tile is written): it was a ValueError, a TypeError part-way through a
    run, or accepted (a seed of 1.7)."""
    import pytest

    from seamless_usd import Options, process_paths, process_stage
    from seamless_usd.errors import UsageError

    assert Options(refine="gan").refine == "gan"
    with pytest.raises(UsageError, match="Options.refine must be one of on, gan, off; got 'yes'"):
        Options(refine="yes")
    with pytest.raises(UsageError, match="Options.tile_size must be one of source, paper"):
        Options().with_(tile_size="2x")
    for bad in ({"seed": 1.7}, {"seed": "abc"}, {"max_size": "128"}, {"jobs": 0}, {"iterations": True},
                {"progress": 5}):
        with pytest.raises(UsageError):
            Options(**bad)
    with pytest.raises(UsageError, match="Options.mode / plan_mode must be a WriteMode"):
        process_paths(["nothing.usda"], Options(mode="dry_run"))
    with pytest.raises(UsageError, match="process_stage"):
        process_paths(None)
    with pytest.raises(UsageError, match="open Usd.Stage"):
        process_stage("scene.usda")
    with pytest.raises(UsageError, match="seamless_usd.Options"):
        process_paths(["nothing.usda"], {"preset": "tiny"})


def test_an_output_folder_that_cannot_be_made_is_refused_before_any_work(tmp_path, capsys):
    import shutil
    from pathlib import Path

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    (tmp_path / "afile").write_text("not a folder")
    scene = tmp_path / "brick" / "scene.usda"
    assert main(["process", str(scene), "--preset", "tiny", "--output-dir", str(tmp_path / "afile" / "sub")]) == 2
    err = capsys.readouterr().err
    assert "--output-dir" in err and "afile@ is a file" in err and "internal error" not in err
    assert sorted(p.name for p in (tmp_path / "brick").iterdir()) == ["scene.usda"]  # nothing done


def test_ctrl_c_that_an_import_reports_as_import_error_ends_the_run_as_interrupted(monkeypatch, capsys):
    """An extension module whose initialisation Ctrl-C breaks raises ImportError("initialization failed"): the run
    still ends as interrupted (exit 130), not as an internal error; an ImportError with no Ctrl-C is one (exit 3)."""
    import os
    import signal
    import time

    import seamless_usd_cli.scan as scan_command
    from seamless_usd_cli.main import main

    def interrupted_import(args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:
            raise ImportError("initialization failed") from None
        return 0

    monkeypatch.setattr(scan_command, "run", interrupted_import)
    # as in a terminal, whatever started the tests (a shell's background job starts with Ctrl-C ignored)
    runner_handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        assert main(["scan", "x.usda"]) == 130
        assert "interrupted" in capsys.readouterr().err
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # put back
    finally:
        signal.signal(signal.SIGINT, runner_handler)

    def broken(args):
        raise ImportError("initialization failed")

    monkeypatch.setattr(scan_command, "run", broken)
    assert main(["scan", "x.usda"]) == 3
    assert "internal error" in capsys.readouterr().err


def test_process_refuses_values_it_cannot_use_before_any_work(tmp_path, capsys):
    """A seed torch cannot take, a pixel limit under 1 and -o beside --in-place: exit 2, named, nothing written."""
    import shutil
    from pathlib import Path

    from seamless_usd_cli.main import main

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    scene = str(tmp_path / "brick" / "scene.usda")
    for args, said in ((["--seed", "-1"], "--seed"), (["--seed", str(1 << 40)], "--seed"),
                       (["--max-pixels", "0"], "--max-pixels"),
                       (["--in-place", "-o", str(tmp_path / "x.usda")], "--in-place")):
        assert main(["process", scene, *args]) == 2, args
        assert said in capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "brick").iterdir()) == ["scene.usda"]


def test_ctrl_c_as_the_command_starts_ends_it_as_interrupted_without_a_traceback(tmp_path):
    """Ctrl-C while the command loads its modules (USD's among them, whose loader printed the tracebacks of an
    interrupt raised inside it and swallowed it) ends the command as interrupted (exit 130), quietly; one that comes
    after the command is done changes nothing."""
    import signal
    import subprocess
    import sys
    import time

    codes = []
    for delay in (0.15, 0.25, 0.4):  # after the interpreter itself has started (about 0.03 s; 0.1 s under load)
        proc = subprocess.Popen([sys.executable, "-m", "seamless_usd_cli.main", "scan", str(tmp_path / "none.usda")],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # as a terminal's
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert "Traceback" not in err.decode(), (delay, err.decode()[-3000:])
        assert proc.returncode in (130, 2), (delay, proc.returncode)  # 2: it had read the missing file already
        assert (proc.returncode == 130) == ("interrupted" in err.decode()), err.decode()
        codes.append(proc.returncode)
    assert 130 in codes


def test_a_reader_that_goes_away_ends_the_command_quietly():
    """``seamless-usd check ... --json | head -c 10``: the JSON's reader closes the pipe; the command ends with
    141 (as one ended by SIGPIPE) and no message, not as an internal error with a crash log."""
    import subprocess
    import sys
    from pathlib import Path

    picture = Path(__file__).resolve().parents[1] / "sample_assets" / "textures" / "brick_albedo.png"
    proc = subprocess.Popen([sys.executable, "-m", "seamless_usd_cli.main", "check", str(picture), "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # gone before anything is written
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert "internal error" not in err and "Traceback" not in err, err


def test_process_on_a_folder_with_no_stage_in_it_is_an_error(tmp_path, capsys):
    """A batch pointed at the wrong folder: exit 2 naming it, as scan and check say; it exited 0 and said nothing."""
    (tmp_path / "notes.txt").write_text("not a stage")
    assert main(["process", "--preset", "tiny", str(tmp_path)]) == 2
    assert "no USD stage or MaterialX document found in this folder" in capsys.readouterr().err


def test_an_unreadable_input_named_relative_is_named_once(tmp_path, monkeypatch, capsys):
    """``process empty.mtlx`` said ``@empty.mtlx@: @/abs/empty.mtlx@: cannot read ...``: the file twice."""
    from seamless_usd_cli.main import main

    (tmp_path / "empty.mtlx").write_text("")
    monkeypatch.chdir(tmp_path)
    assert main(["process", "empty.mtlx"]) == 2
    [line] = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("error:")]
    assert line.count("empty.mtlx@") == 1 and "cannot read the MaterialX document" in line, line


def test_a_library_run_s_lines_name_the_file_each_finding_comes_from(tmp_path, capsys):
    """Two files of a library with the same material path, each missing its texture: the run printed two identical
    ``error: </World/Looks/Wood>: ...`` lines, and the JSON finding named no file."""
    import json

    import numpy as np
    from scenes import ground_scene

    from seamless_usd_cli.main import main

    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        ground_scene(tmp_path / name, np.full((32, 32, 3), 0.5), "wood.png", "Wood")
        (tmp_path / name / "wood.png").unlink()
    main(["process", str(tmp_path), "--dry-run", "--json"])
    captured = capsys.readouterr()
    lines = [ln for ln in captured.err.splitlines() if "</World/Looks/Wood>" in ln and "wood.png" in ln]
    assert len(lines) >= 2 and len(set(lines)) == len(lines), lines
    assert any("a/scene.usda" in ln for ln in lines) and any("b/scene.usda" in ln for ln in lines), lines
    findings = json.loads(captured.out)["findings"]
    assert all(f.get("source") for f in findings), [f for f in findings if not f.get("source")]


def test_the_summary_table_keeps_the_reasons_in_a_terminal_of_80_columns():
    """At 80 columns the reason column was pushed off the edge (rows of blanks) and material paths split mid-word:
    a narrow terminal keeps the material, its status and why."""
    from rich.console import Console

    from seamless_usd.report.model import Report, StackReport, StackStatus
    from seamless_usd_cli.process import _stack_table

    why = "seam in the maps together: vertical line at x=64, rows 96-133 (+0.05)"
    report = Report(sources=["s.usda"], stacks=[
        StackReport(id="1", material="</World/Looks/RotWood>", source="s.usda", status=StackStatus.NOT_PASSED,
                    message=why)])
    for width in (80, 140):
        console = Console(width=width, record=True)
        _stack_table(report, console)
        text = " ".join(console.export_text().replace("│", " ").split())
        assert "</World/Looks/RotWood>" in text and "rows 96-133 (+0.05)" in text, (width, text)


def test_the_summary_ends_with_what_the_run_came_to_in_one_line():
    """After a library's table (and a dry run's plan of thousands of lines) nothing said how many stacks passed,
    failed or were planned, or how many planned ones reuse another's tiles."""
    from seamless_usd.report.model import Report, StackReport, StackStatus
    from seamless_usd_cli.process import _counts_line

    def row(n, status, duplicate_of=None):
        return StackReport(id=str(n), material=f"</M{n}>", source="s.usda", status=status, duplicate_of=duplicate_of)

    run = Report(sources=["s.usda"], stacks=[row(0, StackStatus.PASSED), row(1, StackStatus.NOT_PASSED),
                                             row(2, StackStatus.PASSED), row(3, StackStatus.LEFT_ALONE)])
    assert _counts_line(run) == "4 stacks: 2 passed, 1 not passed, 1 left alone"
    dry = Report(sources=["s.usda"], stacks=[row(0, StackStatus.PLANNED), row(1, StackStatus.PLANNED, "0")])
    assert _counts_line(dry) == "2 stacks: 2 planned (1 reusing another stack's tiles)"
    # a dry run that exits 1 because the cache knows a planned stack will not pass says so in its last line
    known = row(2, StackStatus.PLANNED)
    known.verdict = {"passed": False}
    dry.stacks.append(known)
    assert dry.exit_code == 1
    assert _counts_line(dry) == ("3 stacks: 3 planned (1 reusing another stack's tiles; 1 known from the cache not "
                                 "to pass)")


def test_the_progress_view_keeps_a_bar_for_each_stack_made_at_once_and_no_none_count():
    """With --jobs 2 the second stack's start replaced the first's bar (the first's training then showed on none),
    and a step with no total read "0/None"."""
    from types import SimpleNamespace

    from rich.console import Console

    from seamless_usd.pipeline.options import ProgressEvent
    from seamless_usd_cli.process import _ProgressView

    console = Console(width=140, record=True, force_terminal=True)
    with _ProgressView(console) as view:
        view(ProgressEvent("stack-start", "A", 0, 2))
        view(ProgressEvent("stack-start", "B", 1, 2))
        view(ProgressEvent("train", "A", 0, 2, SimpleNamespace(total=100, iteration=40, it_per_s=9.0)))
        assert set(view.steps) == {"A", "B"}
        tasks = {t.description.strip(): t for t in view.progress.tasks}
        assert tasks["A"].completed == 40 and tasks["A"].total == 100 and tasks["B"].total is None
        view(ProgressEvent("stack-done", "A", 0, 2))
        assert set(view.steps) == {"B"}
    assert "None" not in console.export_text()


def test_progress_in_a_log_file_is_a_line_per_stack_as_it_goes():
    """With stderr in a file (a farm's log) the bars were drawn once, at the end: a run of two hours said nothing
    until it ended. Each stack's start and end is a line, as it happens."""
    from rich.console import Console

    from seamless_usd.pipeline.options import ProgressEvent
    from seamless_usd_cli.process import _ProgressView

    console = Console(width=140, record=True, force_terminal=False)
    with _ProgressView(console) as view:
        view(ProgressEvent("stack-start", "World_Looks_Brick-e1bb29ea54", 0, 2))
        assert console.export_text(clear=False) == "seamless-usd: stack 1/2: World_Looks_Brick-e1bb29ea54\n"
        view(ProgressEvent("stack-done", "World_Looks_Brick-e1bb29ea54", 0, 2, RuntimeError("x")))
    assert console.export_text().splitlines()[-1] == "seamless-usd: stack 1/2 failed"


def test_a_pattern_that_matches_nothing_is_an_unreadable_input_with_its_json_report(tmp_path, capsys, monkeypatch):
    """``process 'lib/*.usd' --json`` printed nothing on stdout where ``process missing.usda --json`` printed its
    report: a pipeline reading stdout could rely on neither. Every command reports both as inputs it cannot read."""
    import jsonschema

    from seamless_usd_schemas import json_schema

    monkeypatch.chdir(tmp_path)
    for command, schema in (("process", "report"), ("scan", "scan"), ("check", "check")):
        assert main([command, "nothing*.usda", "--json"]) == 2, command
        out = capsys.readouterr()
        payload = json.loads(out.out)
        jsonschema.validate(payload, json_schema(schema))
        said = json.dumps(payload)
        assert "nothing*.usda@" in said and "the pattern matches no USD stage" in said, command
    assert main(["process", "nowhere.usda", "--json"]) == 2
    assert "@nowhere.usda@: no such file; check the path" in capsys.readouterr().err


def test_check_takes_a_quoted_pattern_of_pictures(tmp_path, capsys):
    """``check 'textures/*.png'`` (a pattern the shell does not expand: quoted, in a script or a farm's job) said
    'no such file' for the pattern itself."""
    import shutil

    for name in ("brick_albedo.png", "wood_tileable.jpg"):
        shutil.copy(Path(__file__).resolve().parents[1] / "sample_assets" / "textures" / name, tmp_path / name)
    main(["check", str(tmp_path / "*.png"), "--json"])
    payload = json.loads(capsys.readouterr().out)
    assert [Path(i["name"]).name for i in payload["items"]] == ["brick_albedo.png"] and not payload["unreadable"]


def test_a_misspelled_option_is_refused_by_its_sub_command_with_a_guess(capsys):
    """``process X --presett tiny`` printed the top-level usage (``seamless-usd [-h] [--version] COMMAND``) and
    guessed nothing."""
    assert main(["process", "x.usda", "--presett", "tiny"]) == 2
    err = capsys.readouterr().err
    assert "usage: seamless-usd process" in err and "did you mean --preset?" in err
    assert main(["check", "--jsn", "x.png"]) == 2
    assert "seamless-usd check: error: unrecognized arguments: --jsn (did you mean --json?)" in capsys.readouterr().err


def test_a_log_file_says_each_long_stage_of_a_stack_as_it_begins(tmp_path, capsys):
    """A 2K stack spent four minutes cutting, levelling, writing and judging with nothing in the log between its
    start and its end line: each long stage is a line as it begins (and a bar's words on a terminal)."""
    import shutil

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    main(["process", str(tmp_path / "brick" / "scene.usda"), "--preset", "tiny", "--max-size", "128",
          "--cache-dir", str(tmp_path / "cache")])
    lines = [line for line in capsys.readouterr().err.splitlines() if line.startswith("seamless-usd: stack 1/1")]
    assert lines[1:4] == ["seamless-usd: stack 1/1: cutting tiles from the source",
                          "seamless-usd: stack 1/1: writing the maps", "seamless-usd: stack 1/1: judging the written maps"]
