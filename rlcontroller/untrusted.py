"""Reading files from others as data, defensively: an `.npz` by its arrays' headers before any data
(shapes and dtypes checked by the caller, the size bounded), YAML without anchors or aliases. Nothing
read here is unpickled or executed."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import yaml

MAX_ARRAY_BYTES = 256 * 2**20  # the arrays of one .npz, uncompressed
HEADER_READERS = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}


def npz_headers(path: Path, max_bytes: int = MAX_ARRAY_BYTES) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """Each array of an `.npz` by name with its shape and dtype, from the `.npy` headers alone (no data
    read). ValueError (one line) for anything but numeric arrays whose stored bytes are what their header
    declares, or more than `max_bytes` of arrays; OSError or zipfile.BadZipFile for a damaged file."""
    headers = {}
    with zipfile.ZipFile(path) as archive:
        members = archive.infolist()
        total = sum(member.file_size for member in members)
        if total > max_bytes:
            raise ValueError(f"{total:,} bytes of arrays, at most {max_bytes:,} accepted")
        for member in members:
            name = member.filename.removesuffix(".npy")
            if not member.filename.endswith(".npy"):
                raise ValueError(f"{member.filename}: not an array (.npy)")
            with archive.open(member) as stream:
                version = np.lib.format.read_magic(stream)
                if version not in HEADER_READERS:
                    raise ValueError(f"{name}: .npy format version {version} is not read")
                shape, _, dtype = HEADER_READERS[version](stream)
                header_size = stream.tell()
            if dtype.hasobject or dtype.kind not in "fiub":
                raise ValueError(f"{name}: dtype {dtype}, expected numbers")
            declared = int(np.prod(shape, dtype=object)) * dtype.itemsize
            if declared != member.file_size - header_size:
                raise ValueError(
                    f"{name}: its header declares {shape} of {dtype}, the file holds other bytes"
                )
            headers[name] = (tuple(shape), dtype)
    return headers


def read_npz(path: Path) -> dict[str, np.ndarray]:
    """Every array of an `.npz` whose headers were checked (`npz_headers`); never unpickles."""
    with np.load(path, allow_pickle=False) as arrays:
        return {key: arrays[key] for key in arrays.files}


class _NoAliasLoader(yaml.SafeLoader):
    """yaml's safe loader, refusing anchors and aliases."""

    def compose_node(self, parent, index):
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
            raise yaml.YAMLError(f"anchors and aliases are not accepted (line {event.start_mark.line + 1})")
        return super().compose_node(parent, index)


def safe_yaml(text: str):
    """`yaml.safe_load` that also refuses anchors and aliases: a file from others cannot expand itself."""
    loader = _NoAliasLoader(text)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()
