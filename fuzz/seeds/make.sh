#!/bin/sh
# Writes the seed inputs of the fuzz targets into fuzz/seeds/<target>/ (run from the repository
# root; needs python3, and `hbid` built for the model seeds: `cargo build -p hbid`, or HBID=path).
# The text seeds are written out here; the .npy seeds by python3; the model seeds are models
# that `hbid identify` saves, so they follow the current format version.
set -eu
seeds=fuzz/seeds
hbid=${HBID:-${CARGO_TARGET_DIR:-target}/debug/hbid}

mkdir -p "$seeds/text_bytes" "$seeds/npy" "$seeds/model_json" "$seeds/model_bytes"
t=$seeds/text_bytes
printf '# a comment\nt,theta,omega\n0,0.1,0\n0.5,-3.0,1e-3\n1.0,3.1,2\n' > "$t/header.csv"
printf '0;0,1\n0,5;-0,2\n1;0,3\n1,5;3,14\n' > "$t/semicolons.csv"
printf '\xef\xbb\xbf"t"\t"theta"\r\n0\t1\r\n\r\n0.25\t2\r\n0.5\t3\r\n' > "$t/tabs_bom_crlf.txt"
printf '1.5 0.000\n2.5 0.001\n3.5 0.002\n4.5 0.003\n5.5 0.005\n6.5 0.006\n' > "$t/angle_first.txt"
printf 't,x\n0.000,1\n0.001,2\n0.002,3\n0.004,4\n0.005,5\n0.0062,6\n0.007,7\n' > "$t/gap_glitch.csv"
printf '0.1\n0.2\n0.3\n' > "$t/one_column.txt"

python3 - "$seeds/npy" <<'PY'
import struct, sys
out = sys.argv[1]
def npy(descr, shape, fortran, payload, version=1):
    header = "{'descr': '%s', 'fortran_order': %s, 'shape': %s, }" % (
        descr, "True" if fortran else "False", shape)
    size = 2 if version == 1 else 4
    while (8 + size + len(header) + 1) % 64:
        header += " "
    header += "\n"
    length = struct.pack("<H" if version == 1 else "<I", len(header))
    # The fuzz target adds the magic itself; a first byte chooses the read options.
    return bytes([version, 0]) + length + header.encode() + payload
rows = [(0.0, 0.1), (0.5, 0.2), (1.0, 0.3), (1.5, -0.4)]
f8 = b"".join(struct.pack("<dd", *r) for r in rows)
seeds = {
    "f8_c_2d": (0, npy("<f8", "(4, 2)", False, f8)),
    "f8_fortran_2d": (0, npy("<f8", "(4, 2)", True, f8)),
    "f8_1d_step": (1, npy("<f8", "(8,)", False, f8)),
    "f4_2d": (2, npy("<f4", "(4, 2)", False, b"".join(struct.pack("<ff", *r) for r in rows))),
    "i2_1d": (1, npy("<i2", "(3,)", False, struct.pack("<hhh", 1, -2, 4095))),
    "i8_2d_v2": (0, npy("<i8", "(2, 2)", False, struct.pack("<qqqq", 0, 5, 1, 6), version=2)),
    "i4_3col": (2, npy("<i4", "(2, 3)", False, struct.pack("<iiiiii", 0, 1, 2, 1, 2, 3))),
}
for name, (choice, body) in seeds.items():
    with open("%s/%s" % (out, name), "wb") as f:
        f.write(bytes([choice]) + body)
PY

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$hbid" simulate --quiet --samples 3000 --out "$work/p.csv"
"$hbid" simulate --quiet --system duffing --samples 3000 --out "$work/d.csv"
for model in harmonic:p.csv:"" hat:p.csv:"--basis hat:4" polynomial:d.csv:"--signal line --method windowed"; do
    name=${model%%:*}
    rest=${model#*:}
    record=${rest%%:*}
    options=${rest#*:}
    for ext in json bin; do
        # shellcheck disable=SC2086
        "$hbid" identify "$work/$record" --quiet $options --save-model "$work/$name.$ext" > /dev/null 2>&1
    done
    cp "$work/$name.json" "$seeds/model_json/$name.json"
    # The fuzz target adds the magic number and version itself.
    tail -c +13 "$work/$name.bin" > "$seeds/model_bytes/$name"
done
