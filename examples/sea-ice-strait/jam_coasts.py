#!/usr/bin/env python3
"""jam_coasts.py - writes the coasts of the jam scene (jam.yaml) for a constriction W wide.

usage: python3 jam_coasts.py W FILE      e.g. python3 jam_coasts.py 11000 jam-coasts.geojson

A channel 60 km wide (x = 0 to 60 km) north of y = 60 km, a funnel narrowing to W between
y = 60 and 40 km, a straight constriction W wide from y = 40 to 20 km, and a mirror funnel
widening to 60 km again at y = 0 (Damsgaard et al. 2018's strait: funnel, 20 km long
constriction, funnel; Granular.jl examples/strait.jl). Two fixed, non-convex coasts.
"""
import json
import sys


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    w, path = float(sys.argv[1]), sys.argv[2]
    width, top = 60000.0, 125000.0
    a, b = (width - w) / 2, (width + w) / 2
    west = [[-10000, 0], [0, 0], [a, 20000], [a, 40000], [0, 60000], [0, top], [-10000, top]]
    east = [[width + 10000, 0], [width + 10000, top], [width, top], [width, 60000], [b, 40000], [b, 20000],
            [width, 0]]
    feats = []
    for name, ring in (("west coast", west), ("east coast", east)):
        ring = [[round(x), round(y)] for x, y in ring]
        feats.append({"type": "Feature", "properties": {"name": name, "fixed": True},
                      "geometry": {"type": "Polygon", "coordinates": [ring + [ring[0]]]}})
    with open(path, "w") as f:
        f.write('{"type": "FeatureCollection",\n "features": [\n  ')
        f.write(",\n  ".join(json.dumps(ft) for ft in feats))
        f.write("\n ]}\n")


if __name__ == "__main__":
    main()
