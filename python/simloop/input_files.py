"""The files a run reads, and a digest of each one's content: what a worker's
cache of compiled scenes is checked against and what a resumed batch
compares, so that a file edited between two batches is never taken for the
one read before.

A scene is its MJCF file and every file that file may make MuJoCo read:
each attribute whose name starts with "file" (an include, a mesh, a texture
and its six faces, a height field, a skin, a model), resolved against every
folder MuJoCo may look in (the main file's, the including file's, and the
compiler's meshdir, texturedir and assetdir under each), includes followed
into their own files. That is a superset of what MuJoCo opens: a candidate
that does not exist counts, as missing, so a file appearing there later
changes the digest too. The MJCF is scanned as text, not parsed (an XML
parser would expand entities MuJoCo's does not, and a broken file is the
compiler's to report). A scenario adds its file and its CSV inputs.
"""

from __future__ import annotations

import hashlib
import html
import os
import re
from typing import Any, Dict, Iterable, Iterator, List, Optional, Tuple

MISSING = "missing"

# An element's start tag and its attributes, in the MJCF's text.
_TAG = re.compile(rb"<\s*([A-Za-z_][\w.:-]*)((?:[^>\"']|\"[^\"]*\"|'[^']*')*)>")
_ATTRIBUTE = re.compile(rb"([A-Za-z_][\w.:-]*)\s*=\s*(?:\"([^\"]*)\"|'([^']*)')")
_FOLDERS = ("meshdir", "texturedir", "assetdir")
# Elements whose file is MJCF in turn: MuJoCo 2's and 3's <include>, MuJoCo 3's <model> asset.
_MJCF_ELEMENTS = ("include", "model")
# A bound on the files followed, against an include cycle of distinct names.
MAX_FILES = 10_000


def _elements(text: bytes) -> Iterator[Tuple[str, Dict[str, str]]]:
    """(element, {attribute: value}) of each start tag, names in lower case, values unescaped."""
    for tag in _TAG.finditer(text):
        attributes = {}
        for name, double, single in _ATTRIBUTE.findall(tag.group(2)):
            attributes[os.fsdecode(name).lower()] = html.unescape(os.fsdecode(double or single))
        yield os.fsdecode(tag.group(1)).lower(), attributes


def _read(path: str) -> Optional[bytes]:
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError:
        return None


def scene_files(path: str) -> List[str]:
    """The MJCF file `path` (absolute) and every file it may make MuJoCo read, first the file itself."""
    # A compiler's folders in any file apply to assets in every file: scanned again until no new one turns up.
    folders = [""]
    while True:
        found, seen_folders = _scan(path, folders)
        more = [folder for folder in seen_folders if folder not in folders]
        if not more:
            return found
        folders += more


def _scan(path: str, folders: List[str]) -> Tuple[List[str], List[str]]:
    """(the files scene_files names, with assets looked for under `folders`; the compiler folders seen)."""
    main_dir = os.path.dirname(path)
    found: List[str] = [path]
    seen = {path}
    seen_folders: List[str] = []
    queue = [path]
    while queue and len(found) < MAX_FILES:
        current = queue.pop(0)
        text = _read(current)
        if text is None:
            continue
        bases = sorted({main_dir, os.path.dirname(current)})
        for element, attrs in _elements(text):
            for key, value in attrs.items():
                if key in _FOLDERS:
                    seen_folders.append(value)
                if not key.startswith("file") or not value or "\0" in value:
                    continue
                candidates = (
                    [value]
                    if os.path.isabs(value)
                    else [os.path.normpath(os.path.join(base, folder, value)) for base in bases for folder in folders]
                )
                for candidate in candidates:
                    if candidate in seen:
                        continue
                    seen.add(candidate)
                    found.append(candidate)
                    if element in _MJCF_ELEMENTS:
                        queue.append(candidate)
    return found, seen_folders


def scenario_files(scenario: Any) -> List[str]:
    """The files a simloop._core.Scenario read or will read: its CSV inputs, then its scene's (scene_files)."""
    files = [os.path.abspath(f) for f in scenario.csv_files]
    return files + (scene_files(os.path.abspath(scenario.scene)) if scenario.scene else [])


def file_digest(path: str) -> str:
    """sha256 of the file's bytes, or MISSING when it cannot be read (it does not exist, or is not a file)."""
    if not os.path.isfile(path):
        return MISSING
    hasher = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                hasher.update(block)
    except OSError:
        return MISSING
    return hasher.hexdigest()


def digests(paths: Iterable[str]) -> Dict[str, str]:
    """{path: file_digest(path)}, in the order given."""
    return {path: file_digest(path) for path in paths}


def changed(before: Dict[str, str], now: Dict[str, str]) -> List[str]:
    """The paths whose digest differs between two digests(), or that only one of them has."""
    return [path for path in list(before) + [p for p in now if p not in before] if before.get(path) != now.get(path)]
