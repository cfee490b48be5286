"""The way to read a run file without slipfront: the `mcap` package with its
protobuf decoder, message by message, into numpy (what examples/*.py do).
The reference `slipfront.open` is checked and timed against."""

import numpy as np
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

GLOBAL = ("time", "step", "drive_force", "drive_ratio", "friction_force",
          "pinned_fraction", "kinetic_energy", "ruptures")
INTERFACE = ("shear_stress", "normal_stress", "pinned_fraction", "slip", "slip_speed")
BULK = ("ux", "uz", "vx", "vz")


def read(path):
    """{"series": {...}, "interface": {...}, "bulk": {...}} as numpy arrays."""
    rows = {"/global": [], "/interface": [], "/bulk": []}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, m in reader.iter_decoded_messages(topics=list(rows)):
            rows[channel.topic].append(m)
    g, i, b = rows["/global"], rows["/interface"], rows["/bulk"]
    out = {
        "series": {k: np.array([getattr(m, k) for m in g]) for k in GLOBAL},
        "interface": {k: np.array([list(getattr(m, k)) for m in i]) for k in INTERFACE},
        "bulk": {},
    }
    out["interface"]["time"] = np.array([m.time for m in i])
    if b:
        nz, nx = b[0].nz, b[0].nx
        out["bulk"] = {k: np.array([np.asarray(getattr(m, k), dtype=np.float32).reshape(nz, nx)
                                    for m in b]) for k in BULK}
        out["bulk"]["time"] = np.array([m.time for m in b])
    return out
