"""Entry point of the ``seamless-usd`` command: sub-command dispatch and error mapping.

Exit codes: 0 success; 1 some items failed or did not pass (the rest were done); 2 usage error or
unreadable input; 3 internal error (the traceback goes to a log file named in the message); 130 stopped by
Ctrl-C or SIGTERM (what ``kill`` and a farm's scheduler send); 141 the reader of its output went away (``| head``).
"""
from __future__ import annotations

import argparse
import importlib
import os
import sys
import tempfile
import traceback
from collections.abc import Sequence

from seamless_usd.version import __version__
from seamless_usd.errors import SeamlessUsdError

__all__ = ["main", "run", "EXIT_OK", "EXIT_FAILED_ITEMS", "EXIT_USAGE", "EXIT_INTERNAL", "EXIT_PIPE_CLOSED"]

EXIT_OK = 0
EXIT_FAILED_ITEMS = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 3

# Sub-command name -> module with ``add_arguments(parser)`` and ``run(args) -> int``.
COMMANDS: dict[str, str] = {
    "scan": "seamless_usd_cli.scan",
    "process": "seamless_usd_cli.process",
    "check": "seamless_usd_cli.check",
}


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser; ``only``: import and describe that sub-command alone (the others are named
    but their modules, some of which import USD or torch, are not loaded)."""
    parser = argparse.ArgumentParser(
        prog="seamless-usd",
        description="Make the textures of USD / MaterialX materials seamlessly tileable.",
    )
    parser.add_argument("--version", action="version", version=f"seamless-usd {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module_name in COMMANDS.items():
        if only is not None and name != only:
            sub.add_parser(name)
            continue
        module = importlib.import_module(module_name)
        p = sub.add_parser(name, help=module.__doc__.strip().splitlines()[0], description=module.__doc__)
        module.add_arguments(p)
        p.set_defaults(_run=module.run)
        parser.set_defaults(**{f"_parser_{name}": p})
    return parser


def _parse(parser: argparse.ArgumentParser, argv: list[str]) -> argparse.Namespace:
    """``argv`` parsed; an option the sub-command does not know is refused by that sub-command, with its usage and
    the option it most likely means (argparse's own refusal showed the top-level usage and guessed nothing)."""
    import difflib

    args, extra = parser.parse_known_args(argv)
    if extra:
        sub = getattr(args, f"_parser_{args.command}")
        known = [o for action in sub._actions for o in action.option_strings]
        unknown = [e for e in extra if e.startswith("-")]
        guess = difflib.get_close_matches(unknown[0].split("=")[0], known, n=1) if unknown else []
        hint = f" (did you mean {guess[0]}?)" if guess else ""
        sub.error(f"unrecognized arguments: {' '.join(extra)}{hint}")
    return args


def _handle_interrupt(handler) -> dict:
    """Install ``handler`` for Ctrl-C and for SIGTERM (what ``kill`` and a farm's scheduler send) where the default
    ones are installed (the main thread; a host application's own handlers are left alone); returns the previous
    handlers to put back."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {}
    for signum, default in ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, signal.SIG_DFL)):
        if signal.getsignal(signum) is default:
            previous[signum] = signal.signal(signum, handler)
    return previous


def _stopped() -> int:
    """The exit code of a run stopped by Ctrl-C or SIGTERM: 130, as its report says."""
    print("seamless-usd: interrupted", file=sys.stderr)
    return 130


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    interrupted: list[int] = []
    starting = [True]

    def on_interrupt(signum, frame):  # noted: an interrupt some code turns into another error or swallows is one
        interrupted.append(signum)
        if not starting[0]:
            raise KeyboardInterrupt

    previous = _handle_interrupt(on_interrupt)
    try:
        try:
            # Ctrl-C while the sub-command's modules load is held until they have: raised inside USD's module
            # loader, it printed that loader's tracebacks and was swallowed; nothing is done yet (well under a second)
            parser = build_parser(argv[0] if argv and argv[0] in COMMANDS else None)
            args = _parse(parser, argv)
        except SystemExit as exc:  # argparse exits 2 on usage errors, 0 on --help
            return int(exc.code or 0)
        starting[0] = False
        if interrupted:
            raise KeyboardInterrupt
        return int(args._run(args))
    except SeamlessUsdError as exc:
        print(f"seamless-usd: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        return _stopped()
    except BrokenPipeError:  # the reader of stdout went away (``| head``): nothing more is said there
        return _pipe_closed()
    except Exception:  # noqa: BLE001 - the one place unexpected errors are turned into a log file
        if interrupted:  # Ctrl-C inside an extension module's import surfaces as ImportError
            return _stopped()
        with tempfile.NamedTemporaryFile(
            "w", prefix="seamless-usd-crash-", suffix=".log", delete=False
        ) as log:
            traceback.print_exc(file=log)
        print(
            f"seamless-usd: internal error; the traceback is in {log.name} (please report it)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL
    finally:
        import signal

        for signum, handler in previous.items():
            signal.signal(signum, handler)


EXIT_PIPE_CLOSED = 141  # as a command ended by SIGPIPE: 128 + 13


def _pipe_closed() -> int:
    """Stdout pointed at nothing, so that flushing what is left of it at exit raises no second error."""
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError):  # not a real file (captured in a test): nothing to flush there
        pass
    return EXIT_PIPE_CLOSED


def run() -> None:
    """Console-script entry: ``main()``, then a fast exit.

    With torch and OpenImageIO in one process, interpreter shutdown
    makes OpenImageIO's bindings print spurious "nanobind: leaked ..." lines. Every file this
    command writes is complete (atomic) and every cluster closed before ``main`` returns, so the
    process ends with ``os._exit`` after flushing its streams.
    """
    try:
        code = main()
    except KeyboardInterrupt:  # Ctrl-C between main's own handlers (as it starts or returns): nothing half-done
        print("seamless-usd: interrupted", file=sys.stderr)
        code = 130
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        code = _pipe_closed()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    run()
