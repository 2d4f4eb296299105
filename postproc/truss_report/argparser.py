"""truss_report.argparser: the command lines' argument parser: a bad argument is one `error:` line
on stderr and exit 2, like every other input error."""
import argparse
import sys
from typing import NoReturn

from .reading.h5file import EXIT_INPUT_ERROR


class ArgParser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"error: {message} (see {self.prog} --help)\n")
        sys.exit(EXIT_INPUT_ERROR)
