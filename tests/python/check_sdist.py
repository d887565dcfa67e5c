"""Checks that the Python package's source distribution (`maturin sdist`) carries what building the wheel
from it needs: the workspace manifest and lock, both crates, the extension crate and the package, and
the files the binary embeds (presets, schemas, the figures' font)."""

import sys
import tarfile

NEEDED = [
    "pyproject.toml",
    "Cargo.toml",
    "Cargo.lock",
    "src/lib.rs",
    "src/api.rs",
    "crates/core/Cargo.toml",
    "crates/core/src/lib.rs",
    "python/Cargo.toml",
    "python/src/lib.rs",
    "python/trajdrift/__init__.py",
    "python/trajdrift/py.typed",
    "python/trajdrift/_trajdrift.pyi",
    "presets/grandtour.toml",
    "presets/fomo.toml",
    "schemas/drift_error.schema.json",
    "schemas/curvature.schema.json",
    "assets/fonts/DejaVuSans.ttf",
]


def main(path: str) -> None:
    with tarfile.open(path) as tar:
        names = tar.getnames()
    root = names[0].split("/")[0]
    have = {n[len(root) + 1 :] for n in names}
    missing = [n for n in NEEDED if n not in have]
    if missing:
        sys.exit(f"{path}: missing {', '.join(missing)}")
    print(f"{path}: {len(names)} files, everything the wheel's build needs")


if __name__ == "__main__":
    main(sys.argv[1])
