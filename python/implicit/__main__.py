"""`python -m implicit --version`: the package's version (that of the library it was built from).

A quick check that an installed package imports and that its compiled core is the one expected.
"""
import argparse

import implicit


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="python -m implicit",
        description="implicit: implicit sampling for Monte Carlo localization, SLAM and control.")
    parser.add_argument("--version", action="store_true", help="print the version and exit")
    args = parser.parse_args(argv)
    if args.version:
        print(implicit.__version__)
        return 0
    parser.print_help()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
