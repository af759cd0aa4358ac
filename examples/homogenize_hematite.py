"""Hematite coating (seed example 2): FFT homogenization vs Maxwell Garnett, Bruggeman, HS bounds.

Run: ``python examples/homogenize_hematite.py [output_dir]`` (about a minute on 2 cores).
"""

import sys

from nmmm.demo.homogenization import demo

if __name__ == "__main__":
    out = demo(sys.argv[1] if len(sys.argv) > 1 else "out/homogenize")
    print(out["text"])
    for f in out["figures"]:
        print("wrote", f)
