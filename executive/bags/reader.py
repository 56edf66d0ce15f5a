"""Open a recording, whatever it is: a rosbag2 folder, an MCAP file (rosbag2's or dura's)
or a rosbag2 sqlite3 file."""

from __future__ import annotations

from pathlib import Path

from executive.bags.bag import Bag
from executive.bags.mcap_bag import MAGIC, open_mcap
from executive.bags.rosbag2_bag import open_rosbags
from knowledge.errors import BagError, ConfigError
from knowledge.yamlsource import load as load_yaml

SQLITE_MAGIC = b"SQLite format 3\x00"


def open_bag(path: Path) -> Bag:
    """Open the recording at ``path`` (close it when done).

    Raises:
        BagError: there is none, or it is not a recording dura reads, or it is
            truncated or corrupt (one line naming the file and the reason).
    """
    path = Path(path)
    if path.is_dir():
        return _folder(path)
    try:
        with path.open("rb") as f:
            magic = f.read(len(SQLITE_MAGIC))
    except OSError as e:
        raise BagError(f"{path}: cannot read it ({e.strerror or e})") from e
    if magic.startswith(MAGIC):
        return open_mcap(path, [path])
    if magic.startswith(SQLITE_MAGIC):
        return open_rosbags(path, file=True)
    if path.suffix in (".mcap", ".db3"):
        raise BagError(f"{path}: truncated or corrupt (it does not start as a {path.suffix} file)")
    raise BagError(f"{path}: not a ROS 2 bag or an MCAP file")


def _folder(path: Path) -> Bag:
    """Open a rosbag2 folder: its MCAP files read as one, anything else with rosbags."""
    metadata = path / "metadata.yaml"
    if not metadata.is_file():
        raise BagError(f"{path}: not a rosbag2 folder (no metadata.yaml)")
    try:
        # the safe reader: an alias bomb is refused in a moment, before rosbags reads it
        info = load_yaml(metadata)["rosbag2_bagfile_information"]
        storage = str(info["storage_identifier"])
        files = [path / Path(str(name)).name for name in info["relative_file_paths"]]
        compressed = str(info.get("compression_mode") or "").lower() not in ("", "none")
        distro = info.get("ros_distro")
    except ConfigError as e:
        raise BagError(str(e)) from None
    except (KeyError, TypeError) as e:
        raise BagError(f"{metadata}: not rosbag2 metadata ({type(e).__name__}: {e})") from e
    if storage == "mcap" and not compressed:
        missing = [str(f) for f in files if not f.is_file()]
        if missing:
            raise BagError(f"{path}: files of the bag are missing: {', '.join(missing)}")
        return open_mcap(path, files, str(distro) if distro else None)
    return open_rosbags(path)
