"""Read the /interface channel of a slipfront run file into numpy arrays.

    pip install -r examples/requirements.txt
    python3 examples/read_interface.py run.mcap

A file cut short (a killed run) has no summary, which these readers need:
run `slipfront recover run.mcap` first (slipfront's own info and plot read
it as it is).
"""
import sys

import numpy as np
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory


def read_interface(path):
    """Times (s), block spacing (m) and the per-block fields, time × x."""
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        spacing = float(next(
            m.metadata["spacing"] for m in reader.iter_metadata()
            if m.name == "slipfront"))
        rows = [m for _, _, _, m in
                reader.iter_decoded_messages(topics=["/interface"])]
    if not rows:
        raise ValueError(f"{path}: no /interface messages")
    fields = {name: np.array([getattr(m, name) for m in rows])
              for name in ("pinned_fraction", "shear_stress",
                           "normal_stress", "slip", "slip_speed")}
    return np.array([m.time for m in rows]), spacing, fields


if __name__ == "__main__":
    t, spacing, f = read_interface(sys.argv[1])
    print(f"{len(t)} samples from {t[0]:.6e} to {t[-1]:.6e} s, "
          f"{f['pinned_fraction'].shape[1]} blocks {spacing:g} m apart, "
          f"mean pinned fraction {f['pinned_fraction'].mean():.4f}")
