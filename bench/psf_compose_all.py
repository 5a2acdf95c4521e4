#!/usr/bin/python3
# The reference's `all` term as its (deterministic) single term plus its (Monte Carlo) multiple
# term, so that bench/psf.sh renders each Monte Carlo reference once: compose SINGLE MULTIPLE OUT.
# OUT's standard error (OUT with .stderr before the extension, as `scatterd bench` reads it) is
# the multiple term's. Needs Debian's python3-openimageio and python3-numpy (/usr/bin/python3).
import shutil
import sys

import OpenImageIO as oiio


def read(path):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        sys.exit(f"psf_compose_all: {path}: {buf.geterror()}")
    return buf


def stderr_path(path):
    stem, dot, ext = path.rpartition(".")
    return f"{stem}.stderr.{ext}"


single, multiple, out = sys.argv[1:4]
total = oiio.ImageBufAlgo.add(read(single), read(multiple))
if not total.write(out):
    sys.exit(f"psf_compose_all: {out}: {total.geterror()}")
shutil.copyfile(stderr_path(multiple), stderr_path(out))
