#!/usr/bin/env python3
"""Writes the seed inputs of fuzz_ingest (test/fuzz/corpus/ingest/seed_*).

Run by hand when the encoding of fuzz_ingest.cpp changes:
  /usr/bin/python3 test/fuzz/make_seeds.py MEASUREMENTS.csv
(MEASUREMENTS.csv: e.g. `synthesize_bag --config config/speed_bump.yaml
--output /tmp/x.bag --csv MEASUREMENTS.csv`). The bag seeds are made by
make_bag_seeds.sh.

fuzz_ingest decodes with FuzzedDataProvider, whose integer reads take bytes
from the END of the input, most significant byte first; so the values are
listed in decoding order and the byte string is reversed at the end.
"""
import csv
import math
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "corpus", "ingest")


class Seed:
    def __init__(self, paper):
        self.ops = []  # bytes in consumption order
        self.u8(1 if paper else 0)

    def u8(self, v):
        self.ops.append(v & 0xFF)

    def u16(self, v):
        self.ops += [(v >> 8) & 0xFF, v & 0xFF]

    def u64(self, v):
        self.ops += [(v >> (8 * (7 - i))) & 0xFF for i in range(8)]

    def raw(self, x):
        self.u64(struct.unpack("<Q", struct.pack("<d", x))[0])

    def value(self, x):
        self.u8(0xC0)  # raw bit pattern
        self.raw(x)

    def special(self, index):
        self.u8(128 + index)

    def sample(self, dt_steps, mask, values, time_mode=0, raw_time=None):
        self.u8(time_mode)
        if time_mode in (0, 2):
            self.u16(dt_steps)
        elif time_mode == 3:
            self.raw(raw_time)
        self.u8(mask)
        for v in values:
            if isinstance(v, tuple):
                self.special(v[1])
            else:
                self.value(v)

    def write(self, name):
        with open(os.path.join(OUT, "seed_" + name), "wb") as f:
            f.write(bytes(reversed(self.ops)))


def main():
    rows = []
    with open(sys.argv[1]) as f:
        for r in csv.DictReader(f):
            rows.append([float(r[k]) for k in ("t", "u1", "u2", "v1", "v2")])
    os.makedirs(OUT, exist_ok=True)
    for paper in (False, True):
        s = Seed(paper)
        t = 0.0
        for r in rows[:40]:
            steps = int(round((r[0] - t) / 1e-4))
            t += steps * 1e-4
            s.sample(steps, 0x0F, r[1:])
        s.write(("paper" if paper else "square_root") + "_trajectory")
    # Channel subsets, zero interval, backwards and raw times, specials.
    s = Seed(False)
    r = rows[0]
    s.sample(3000, 0x01, [r[1]])
    s.sample(0, 0x08, [r[4]], time_mode=1)  # same time, other channel
    s.sample(3000, 0x00, [])  # no channel: forecast only
    s.sample(100, 0x06, [r[2], r[3]], time_mode=2)  # backwards: rejected
    s.sample(0, 0x0F, [(0, 0), r[2], r[3], r[4]], time_mode=0)  # NaN: rejected
    s.sample(0, 0x03, [(0, 1), (0, 2)])  # +-Inf: rejected
    s.sample(0, 0x03, [(0, 3), (0, 6)])  # denormal, max
    s.sample(0, 0x03, [(0, 11), (0, 12)], time_mode=3, raw_time=math.inf)
    s.sample(3000, 0x0F, [0.0, 0.0, 0.0, 0.0])
    s.write("edge_cases")
    # Raw channel lists: duplicates, disorder, out of range, length mismatch.
    s = Seed(True)
    s.u8(0)  # time: step
    s.u16(3000)
    s.u8(0x80)  # raw channel list
    s.u8(3)  # three channels
    for c in (1, 1, 5):  # duplicate and out of range (decoded as -2 + byte % 8)
        s.u8(c + 2)
    for x in (0.01, 0.01, 0.2):
        s.value(x)
    s.sample(3000, 0x40 | 0x03, [])  # mask u1, u2 with an explicit value count:
    s.u8(3)  # three values for two channels
    for x in (0.01, 0.02, 0.03):
        s.value(x)
    s.write("channel_lists")


if __name__ == "__main__":
    main()
