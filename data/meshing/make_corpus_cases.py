#!/usr/bin/env python3
"""Writes the case list of the meshing regression corpus (corpus.json) WITHOUT expectations.

Run once to (re)create the list; then fill in the expected figures with
    SD_UPDATE_MESHING_CORPUS=1 ctest -R MeshingCorpus    (see docs/meshing.md)
Deterministic: a fixed seed, so the same list comes out every time.
"""
import json
import random
import sys

rng = random.Random(20240611)


def even(counts):
    """Makes the total even by adding 1 to the shortest side (never to zero)."""
    if sum(counts) % 2:
        i = counts.index(min(counts))
        counts[i] += 1
    return counts


cases = []


def add(family, counts):
    counts = even(list(counts))
    name = f"{family}-n{len(counts)}-{sum(1 for c in cases if c['family'] == family and len(c['sides']) == len(counts))}"
    cases.append({"name": name, "family": family, "sides": counts})


# The figures Takayama, Panozzo & Sorkine-Hornung (2014) report; we must never be worse.
for counts in ([3, 3, 4], [5, 5, 6], [5, 6, 3, 6, 4], [3, 3, 3, 3, 4], [6, 4, 4, 2], [10, 4, 4, 2],
               [2, 2, 2, 2, 2, 2], [4, 3, 3, 4, 3, 3], [2, 8, 4], [4, 4, 4, 4]):
    add("reference", counts)

for n in range(2, 11):
    for _ in range(9):
        add("fair", [rng.randint(4, 12) for _ in range(n)])
    for _ in range(4):
        counts = [rng.randint(2, 6) for _ in range(n)]
        counts[rng.randrange(n)] = rng.randint(30, 60)
        add("one-long", counts)
    for _ in range(3):
        counts = [rng.randint(2, 6) for _ in range(n)]
        i = rng.randrange(n)
        j = (i + rng.randint(1, n - 1)) % n
        counts[i], counts[j] = rng.randint(20, 40), rng.randint(20, 40)
        add("two-long", counts)
    for _ in range(2):
        add("alternating", [rng.randint(12, 24) if k % 2 == 0 else rng.randint(1, 4) for k in range(n)])
    add("all-ones", [1] * n if n > 2 else [1, 3])
    for _ in range(3):
        add("large", [rng.randint(30, 60) for _ in range(n)])

# Small skewed regions where a layout with a reflex boundary vertex (valence 4) reaches
# |n - 4| (the two the issue names first), and more at random with sides of 1..5 edges.
for counts in ([1, 2, 3, 1, 3], [2, 4, 4, 2, 4]):
    add("skewed-small", counts)
for n in range(3, 7):
    for _ in range(5):
        add("skewed-small", [rng.randint(1, 5) for _ in range(n)])

# Notched regions (tests/meshing/patch_fill_checks.hpp, notched_sides: corner 1 pulled in to
# a reflex angle, every side bowed in by 2%), filled in 3D: never an inverted quad.
for n, degrees in ((4, 195), (5, 195), (6, 195), (4, 200), (5, 200)):
    for _ in range(3):
        counts = even([rng.randint(5, 10) for _ in range(n)])
        cases.append({"name": f"notched-n{n}-{degrees}-{_}", "family": "notched", "sides": counts,
                      "reflex_corner_deg": degrees})

# Chevrons at 210 deg (issue 22): every quadrilateral and pentagon of the concave test's range
# that still folded before the foldover-free placement, the one whose folded cluster went
# unseen ((5,10,6,5)), the thinnest since ((10,6,6,8)), and three more at random per n.
folded_at_210 = [
    [5, 10, 6, 5], [8, 5, 9, 6], [10, 6, 10, 6], [9, 7, 10, 6], [10, 10, 10, 6], [5, 8, 8, 7],
    [6, 8, 9, 7], [10, 5, 10, 7], [10, 5, 5, 8], [9, 5, 8, 8], [8, 6, 8, 8], [6, 8, 8, 8],
    [9, 6, 9, 8], [7, 8, 9, 8], [6, 9, 9, 8], [5, 10, 9, 8], [6, 10, 10, 8], [8, 6, 7, 9],
    [10, 6, 7, 9], [5, 10, 8, 9], [7, 9, 9, 9], [6, 10, 9, 9], [10, 6, 8, 10], [8, 9, 9, 10],
    [9, 9, 10, 10], [8, 10, 10, 10], [10, 10, 5, 8, 5], [10, 10, 5, 10, 5], [10, 10, 6, 8, 6],
]
for i, counts in enumerate(folded_at_210):
    cases.append({"name": f"notched-n{len(counts)}-210-folded-{i}", "family": "notched",
                  "sides": counts, "reflex_corner_deg": 210})
cases.append({"name": "notched-n4-210-thinnest", "family": "notched", "sides": [10, 6, 6, 8],
              "reflex_corner_deg": 210})
for n in (4, 5):
    for _ in range(3):
        counts = even([rng.randint(5, 10) for _ in range(n)])
        cases.append({"name": f"notched-n{n}-210-{_}", "family": "notched", "sides": counts,
                      "reflex_corner_deg": 210})

# One case per line, so that a diff shows which figures changed.
lines = [json.dumps(c) for c in cases]
sys.stdout.write('{"format": "sketchdrape-meshing-corpus/1",\n "cases": [\n  ' + ",\n  ".join(lines) + "\n ]\n}\n")
