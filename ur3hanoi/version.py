"""The version of ur3hanoi: its one home. ``pyproject.toml`` reads it when the package is built (setuptools'
``attr:``, read from this file's text without importing the package); the package face re-exports it as
``ur3hanoi.__version__``; the files ur3hanoi writes and its cache keys name it. It imports nothing, so any layer may
import it."""

__version__ = "0.1.0"
