"""The ``seamless-usd`` command (installed as the ``seamless_usd_cli`` package)."""
