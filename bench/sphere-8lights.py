#!/usr/bin/env python3
# Writes OUT/sphere-8lights.json: scenes/sphere.json with its light replaced by 8 point lights of an
# eighth of its intensity on a circle around the sphere (the 1-against-8-lights frame times).
import json, math, sys

out = sys.argv[1]
scene = json.load(open("scenes/sphere.json"))
light = scene["lights"][0]
scene["lights"] = [dict(light, position=[3 * math.cos(2 * math.pi * k / 8), 2.0, 3 * math.sin(2 * math.pi * k / 8)],
                        intensity=light["intensity"] / 8) for k in range(8)]
json.dump(scene, open(f"{out}/sphere-8lights.json", "w"))
