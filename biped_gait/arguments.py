"""Command-line parsing shared by the project's commands."""

from __future__ import annotations

import argparse


class OneLineParser(argparse.ArgumentParser):
    """Bad usage is one line on stderr and exit status 2, like every other input error."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")
