from seamless_usd_cli.main import main


def test_version_and_help_exit_zero(capsys):
    assert main(["--version"]) == 0
    assert "seamless-usd" in capsys.readouterr().out


def test_unknown_command_is_a_usage_error(capsys):
    assert main(["frobnicate"]) == 2
    assert "invalid choice" in capsys.readouterr().err


def test_options_refuse_unknown_refine_and_tile_size_modes():
    import pytest

    from seamless_usd import Options

    assert Options(refine="gan").refine == "gan"
    with pytest.raises(ValueError, match="Options.refine must be one of on, gan, off; got 'yes'"):
        Options(refine="yes")
    with pytest.raises(ValueError, match="Options.tile_size must be one of source, paper"):
        Options().with_(tile_size="2x")
