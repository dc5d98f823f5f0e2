from seamless_usd_cli.main import main


def test_version_and_help_exit_zero(capsys):
    assert main(["--version"]) == 0
    assert "seamless-usd" in capsys.readouterr().out


def test_unknown_command_is_a_usage_error(capsys):
    assert main(["frobnicate"]) == 2
    assert "invalid choice" in capsys.readouterr().err
