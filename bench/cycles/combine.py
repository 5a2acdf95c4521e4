#!/usr/bin/python3
"""Mean and standard error of independent renders of one scene (other seeds), pixel by pixel.

Usage: combine.py OUT.exr IN1.exr IN2.exr ... : writes OUT.exr (the mean) and OUT.stderr.exr (the
standard error of the mean, from the spread of the inputs), and prints the relative noise of one
input, ||std|| / ||mean|| over the covered pixels, as JSON.
"""
import json
import sys

import numpy as np
import OpenImageIO as oiio

from compare import read


def write(path, px):
    spec = oiio.ImageSpec(px.shape[1], px.shape[0], 3, "float")
    out = oiio.ImageOutput.create(path)
    out.open(path, spec)
    out.write_image(np.ascontiguousarray(px, dtype=np.float32))
    out.close()


def main():
    out, inputs = sys.argv[1], sys.argv[2:]
    if len(inputs) < 2:
        sys.exit("combine: needs at least two renders")
    stack = np.stack([read(p) for p in inputs])
    mean, std = stack.mean(axis=0), stack.std(axis=0, ddof=1)
    write(out, mean)
    write(out[: -len(".exr")] + ".stderr.exr", std / np.sqrt(len(inputs)))
    covered = mean.max(axis=2) > 0
    print(json.dumps({"runs": len(inputs),
                      "noise_one": float(np.linalg.norm(std[covered]) / np.linalg.norm(mean[covered]))}))


if __name__ == "__main__":
    main()
