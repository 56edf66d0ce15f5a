"""Open a recording, whatever it is: a rosbag2 folder (any metadata version up to 9,
Jazzy's; sqlite3 or MCAP, split into several files, compressed per file or per
message), an MCAP file (rosbag2's or dura's, whole or cut off) or a rosbag2 sqlite3
file.

Of ``metadata.yaml`` only the storage, the files, the compression and the ROS
distribution are used: topics, counts and times come from the files themselves.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from executive.bags.bag import Bag
from executive.bags.mcap_bag import MAGIC, open_mcap
from executive.bags.rosbag2_bag import open_sqlite3
from knowledge.errors import BagError, ConfigError
from knowledge.yamlsource import load as load_yaml

SQLITE_MAGIC = b"SQLite format 3\x00"
MAX_VERSION = 9  # the newest rosbag2 metadata version read (Jazzy's; Foxy wrote 4)


def open_bag(path: Path, types: Mapping[str, Any] | None = None) -> Bag:
    """Open the recording at ``path`` (close it when done).

    Args:
        types: message definitions besides the bag's own (see :func:`read_types`).

    Raises:
        BagError: there is none, or it is not a recording dura reads, or it is
            truncated or corrupt (one line naming the file and the reason).
    """
    path = Path(path)
    if path.is_dir():
        return _folder(path, types)
    try:
        with path.open("rb") as f:
            magic = f.read(len(SQLITE_MAGIC))
    except OSError as e:
        raise BagError(f"{path}: cannot read it ({e.strerror or e})") from e
    if magic.startswith(MAGIC):
        return open_mcap(path, [path], extra_types=types)
    if magic.startswith(SQLITE_MAGIC):
        return open_sqlite3(path, [path], extra_types=types)
    if path.suffix in (".mcap", ".db3"):
        raise BagError(f"{path}: truncated or corrupt (it does not start as a {path.suffix} file)")
    raise BagError(f"{path}: not a ROS 2 bag or an MCAP file")


def _folder(path: Path, types: Mapping[str, Any] | None) -> Bag:
    """Open a rosbag2 folder: its files read as one."""
    metadata = path / "metadata.yaml"
    if not metadata.is_file():
        raise BagError(f"{path}: not a rosbag2 folder (no metadata.yaml)")
    try:
        # the safe reader: an alias bomb is refused in a moment, before rosbags reads it
        info = load_yaml(metadata)["rosbag2_bagfile_information"]
        version = int(info.get("version", 0))
        storage = str(info["storage_identifier"])
        files = [path / Path(str(name)).name for name in info["relative_file_paths"]]
        mode = str(info.get("compression_mode") or "").lower()
        fmt = str(info.get("compression_format") or "").lower()
        distro = str(info["ros_distro"]) if info.get("ros_distro") else None
    except ConfigError as e:
        raise BagError(str(e)) from None
    except (KeyError, TypeError, ValueError) as e:
        raise BagError(f"{metadata}: not rosbag2 metadata ({type(e).__name__}: {e})") from e
    if version > MAX_VERSION:
        raise BagError(f"{metadata}: metadata version {version}: dura reads 1 to {MAX_VERSION}")
    mode = "" if mode == "none" else mode
    if mode and fmt != "zstd":
        raise BagError(f"{metadata}: compressed with '{fmt}': dura reads zstd only")
    if mode not in ("", "file", "message"):
        raise BagError(f"{metadata}: compression mode '{mode}' is not rosbag2's")
    missing = [str(f) for f in files if not f.is_file()]
    if missing:
        raise BagError(f"{path}: files of the bag are missing: {', '.join(missing)}")
    if storage == "mcap":
        return open_mcap(path, files, distro, compression=mode, extra_types=types)
    if storage == "sqlite3":
        return open_sqlite3(path, files, distro=distro, compression=mode, extra_types=types)
    raise BagError(f"{metadata}: storage '{storage}': dura reads sqlite3 and mcap")


def read_types(paths: Sequence[Path]) -> dict[str, Any]:
    """Read the message definitions under ``paths``: ``.msg``, ``.srv`` and ``.action``
    files laid out as in a ROS package (as the robot description's ``ros2: messages:``),
    and ``.idl`` files.

    Raises:
        BagError: a path is missing or a definition invalid (``file:line: reason``).
    """
    from rosbags.typesys import Stores, get_types_from_idl, get_typestore

    from knowledge.ros2_messages import read_definitions, register  # with rosbags

    known = dict(get_typestore(Stores.LATEST).fielddefs)
    definitions, findings = read_definitions(paths, known)
    if findings:
        raise BagError(f"--types: {findings[0]}")
    store = get_typestore(Stores.EMPTY)
    register(store, definitions)
    found = dict(store.fielddefs)
    for file in sorted({f for p in paths for f in ([p] if p.is_file() else p.rglob("*.idl"))}):
        if file.suffix != ".idl":
            continue
        try:
            found.update(get_types_from_idl(file.read_text(encoding="utf-8")))
        except Exception as e:  # rosbags' parser fails in many ways on a bad text
            first = (str(e).strip().splitlines() or [""])[0]
            raise BagError(f"--types: {file}: cannot read it ({type(e).__name__}: {first})") from e
    return found
