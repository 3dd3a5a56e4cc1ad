"""python -m xcheck run SCENE --out DIR [--end-time T] (under mpiexec -n N)."""

import argparse
import sys

from . import run


def main():
    p = argparse.ArgumentParser(prog="xcheck")
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run a scene on the MPI ranks of this job")
    r.add_argument("scene")
    r.add_argument("--out", required=True)
    r.add_argument("--end-time", type=float)
    a = p.parse_args()
    sys.exit(run.main(a.scene, a.out, a.end_time))


main()
