#!/usr/bin/env bash
# Packages the library crates as crates.io would take them (`cargo package --no-verify`: the
# packages are not built, their quadray dependencies are not on crates.io) and checks that every
# file a crate's source includes (`include_str!`, `include_bytes!`: WGSL, the default scene) is
# inside its package. Needs the crates.io index (network); not part of the test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
crates=(quadray-core quadray-gpu quadray-shadows quadray-indirect quadray-displace quadray-bevy)
cargo package --no-verify --allow-dirty "${crates[@]/#/-p}"
python3 - "${crates[@]}" <<'PY'
import os, re, sys, tarfile
missing = []
for crate in sys.argv[1:]:
    with tarfile.open(f"target/package/{crate}-0.1.0.crate") as tar:
        packaged = set(tar.getnames())
    root = f"crates/{crate}"
    for dirpath, _, files in os.walk(f"{root}/src"):
        for name in files:
            if not name.endswith(".rs"):
                continue
            text = open(os.path.join(dirpath, name)).read()
            for target in re.findall(r'include_(?:str|bytes)!\("([^"]+)"\)', text):
                path = os.path.normpath(os.path.join(dirpath, target))
                inside = f"{crate}-0.1.0/" + os.path.relpath(path, root)
                if inside not in packaged:
                    missing.append(f"{crate}: {os.path.join(dirpath, name)} includes {target}")
    print(f"{crate}: {len(packaged)} files")
if missing:
    sys.exit("not in the package:\n" + "\n".join(missing))
print("every included file is packaged")
PY
