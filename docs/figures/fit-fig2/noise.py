"""A synthetic "measured" friction curve for docs/results.md (worked calibration): the
mean friction per junction of a sweep (sweep.csv) plus Gaussian noise of 10 % of each
value, seeded; writes data.csv (plate.v, friction, sigma) on stdout.

    python3 docs/figures/fit-fig2/noise.py out/fig2-truth/sweep.csv > docs/figures/fit-fig2/data.csv
"""
import csv
import random
import sys

RELATIVE = 0.10
rng = random.Random(2026)
print("plate.v,friction,sigma")
for row in csv.DictReader(open(sys.argv[1])):
    f = float(row["friction_per_junction"])
    s = RELATIVE * f
    print(f"{row['plate.v']},{f + rng.gauss(0.0, s)!r},{s!r}")
