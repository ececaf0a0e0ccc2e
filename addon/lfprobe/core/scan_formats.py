"""Scan formats read through Python libraries instead of the native readers: E57 (pye57, which
wraps libE57Format) and LAS/LAZ (laspy with the lazrs backend). Each file becomes one or more
ScanArrays in world coordinates held in double, so that georeferenced coordinates keep their
precision until the merge subtracts the world offset (docs/DESIGN.md §3).

The libraries are optional: they are imported only when such a file is read, looked for on
sys.path first and then in the folders where tools/setup.sh installs them (build/pydeps of the
checkout, or $LFPROBE_PYDEPS), so .xyz/.pts/.ply work without them and an E57 or LAS without
them is a clear error saying what to install."""

from __future__ import annotations

import importlib
import os
import sys
from dataclasses import dataclass, field
from typing import Callable, List, Optional

import numpy as np

from . import colour
from .errors import InputError

# Versions tools/setup.sh installs (tools/scan_deps.sh); the readers use only long-stable API.
PINNED = {"pye57": "0.4.19", "pyquaternion": "0.9.9", "laspy": "2.7.0", "lazrs": "0.8.2"}
E57_EXTENSIONS = (".e57",)
LAS_EXTENSIONS = (".las", ".laz")
LIBRARY_EXTENSIONS = E57_EXTENSIONS + LAS_EXTENSIONS
NATIVE_EXTENSIONS = (".xyz", ".txt", ".asc", ".csv", ".pts", ".ply")
ALL_EXTENSIONS = NATIVE_EXTENSIONS + LIBRARY_EXTENSIONS

# realpath: Blender may load the add-on through a link to the checkout's addon/lfprobe.
_CHECKOUT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__)))))


class MissingLibraryError(InputError):
    """A scan format's Python library is not installed."""


class ScanFileError(InputError):
    """A scan file the library cannot read, or whose contents contradict its header."""


@dataclass
class ScanArrays:
    """One scan (a file, or one station of an E57) in world coordinates.
    positions: (n, 3) float64 world; colors: (n, 3) float32 linear RGB or None;
    intensities: (n,) float32 as the file stores them, or None; scanner: the station's world
    position or None; metadata: what the manifest records beside the file (station name,
    CRS, ...)."""

    path: str
    positions: np.ndarray
    colors: Optional[np.ndarray] = None
    intensities: Optional[np.ndarray] = None
    scanner: Optional[tuple] = None
    metadata: dict = field(default_factory=dict)


def pydeps_folders() -> List[str]:
    """Where tools/setup.sh installs the optional libraries: $LFPROBE_PYDEPS (os.pathsep
    separated), then build/pydeps of the checkout this package lives in."""
    folders = [f for f in os.environ.get("LFPROBE_PYDEPS", "").split(os.pathsep) if f]
    folders.append(os.path.join(_CHECKOUT, "build", "pydeps"))
    return [f for f in folders if os.path.isdir(f)]


def library(name: str, purpose: str):
    """Imports an optional library, adding pydeps_folders() to sys.path when it is not found
    on it; raises MissingLibraryError saying what to install."""
    try:
        return importlib.import_module(name)
    except ImportError:
        pass
    for folder in pydeps_folders():
        if folder not in sys.path:
            sys.path.append(folder)
    try:
        return importlib.import_module(name)
    except ImportError as error:
        wanted = {"pye57": ["pye57", "pyquaternion"], "laspy": ["laspy", "lazrs"],
                  "lazrs": ["laspy", "lazrs"]}.get(name, [name])
        pins = " ".join(f"{p}=={PINNED[p]}" for p in wanted if p in PINNED)
        raise MissingLibraryError(
            f"{purpose} needs the Python package {name}, which is not installed ({error}). "
            f"Run `bash tools/scan_deps.sh` in the lfprobe checkout (installs {pins} into build/pydeps), "
            f"or `python3 -m pip install {pins}` for the Python that runs lfprobe"
        ) from error


def is_library_format(path: str) -> bool:
    return str(path).lower().endswith(LIBRARY_EXTENSIONS)


def read_scan_arrays(path: str, progress: Optional[Callable[[float, str], object]] = None) -> List[ScanArrays]:
    """Reads an E57 (one ScanArrays per station) or a LAS/LAZ (one) file."""
    path = str(path)
    if not os.path.isfile(path):
        raise ScanFileError(f"{path}: no such file")
    lower = path.lower()
    if lower.endswith(E57_EXTENSIONS):
        return read_e57(path, progress)
    if lower.endswith(LAS_EXTENSIONS):
        return [read_las(path)]
    raise ScanFileError(f"{path}: not an E57 or LAS/LAZ file")


# ---------------------------------------------------------------------------------------- sRGB


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] → linear, float32 (what the native readers do with 8-bit
    scan colours): core/colour.py's curve."""
    return colour.srgb_decode(encoded).astype(np.float32)


def quaternion_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The rotation of a unit quaternion (w, x, y, z), normalised first (E57 poses are stored
    to finite precision)."""
    q = np.array([w, x, y, z], dtype=np.float64)
    norm = np.linalg.norm(q)
    if not np.isfinite(norm) or norm == 0.0:
        raise ValueError(f"a pose rotation of zero length {tuple(q)}")
    w, x, y, z = q / norm
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


# ----------------------------------------------------------------------------------------- E57


def _e57_number(node):
    """The value of an E57 numeric node (float, integer or scaled integer)."""
    kind = node.type()
    libe57 = sys.modules["pye57.libe57"]
    if kind == libe57.NodeType.E57_SCALED_INTEGER:
        return float(libe57.ScaledIntegerNode(node).scaledValue())
    if kind == libe57.NodeType.E57_INTEGER:
        return float(libe57.IntegerNode(node).value())
    if kind == libe57.NodeType.E57_FLOAT:
        return float(libe57.FloatNode(node).value())
    raise ValueError(f"{node.pathName()} is not a number")


def _e57_child(structure, name: str):
    return structure.get(name) if structure.isDefined(name) else None


def _e57_string(structure, name: str) -> Optional[str]:
    node = _e57_child(structure, name)
    if node is None:
        return None
    libe57 = sys.modules["pye57.libe57"]
    return libe57.StringNode(node).value() if node.type() == libe57.NodeType.E57_STRING else None


def _e57_field_range(libe57, scan, prototype, name: str, limits: str) -> tuple:
    """(minimum, maximum) of a colour or intensity field: the scan's colorLimits /
    intensityLimits when given, else the field's own range (integer fields), else [0, 1]."""
    if scan.isDefined(limits):
        box = libe57.StructureNode(scan.get(limits))
        base = name[0].lower() + name[1:] if name.startswith("color") else name
        low, high = _e57_child(box, base + "Minimum"), _e57_child(box, base + "Maximum")
        if low is not None and high is not None:
            return _e57_number(low), _e57_number(high)
    node = prototype.get(name)
    if node.type() == libe57.NodeType.E57_INTEGER:
        integer = libe57.IntegerNode(node)
        return float(integer.minimum()), float(integer.maximum())
    if node.type() == libe57.NodeType.E57_SCALED_INTEGER:
        scaled = libe57.ScaledIntegerNode(node)
        return float(scaled.scaledMinimum()), float(scaled.scaledMaximum())
    return 0.0, 1.0


def _normalised(values: np.ndarray, low: float, high: float) -> np.ndarray:
    span = high - low
    if not np.isfinite(span) or span <= 0.0:
        return np.clip(values, 0.0, 1.0)
    return np.clip((values - low) / span, 0.0, 1.0)


def read_e57(path: str, progress=None) -> List[ScanArrays]:
    """Every scan (station) of an E57 file: cartesian or spherical records, invalid points
    dropped, the pose (rotation quaternion, translation) applied in double, the station's
    position (the pose's translation) as the scanner of its points, colour normalised by the
    file's colour limits (8-bit, 16-bit or float) and decoded from sRGB, intensity as stored."""
    pye57 = library("pye57", f"{path}: reading E57")
    libe57 = pye57.libe57
    try:
        image = libe57.ImageFile(path, "r")
    except Exception as error:  # libE57's E57Exception and friends: all mean an unreadable file
        raise ScanFileError(f"{path}: not a readable E57 file ({_e57_reason(error)})") from error
    try:
        root = image.root()
        coordinate_metadata = _e57_string(root, "coordinateMetadata") or ""
        data3d = libe57.VectorNode(root.get("/data3D"))
        count = data3d.childCount()
        if count == 0:
            raise ScanFileError(f"{path}: the E57 file holds no 3D scans")
        scans = []
        for index in range(count):
            if progress is not None and progress(index / count, f"reading {os.path.basename(path)}") is False:
                raise InputError(f"{path}: reading cancelled")
            scans.append(_read_e57_scan(libe57, image, path, index, libe57.StructureNode(data3d.get(index))))
            if coordinate_metadata:
                scans[-1].metadata["crs"] = coordinate_metadata
        return scans
    except InputError:
        raise
    except Exception as error:
        raise ScanFileError(f"{path}: a damaged or truncated E57 file ({_e57_reason(error)})") from error
    finally:
        try:
            image.close()
        except Exception:  # closing a damaged file can fail again; the first error is the one to tell
            pass


def _e57_reason(error: Exception) -> str:
    text = str(error).strip().splitlines()
    return text[0] if text else type(error).__name__


def _read_e57_scan(libe57, image, path: str, index: int, scan) -> ScanArrays:
    points = libe57.CompressedVectorNode(scan.get("points"))
    prototype = libe57.StructureNode(points.prototype())
    names = {prototype.get(i).elementName() for i in range(prototype.childCount())}
    n = int(points.childCount())
    label = f"{path} scan {index}"
    if {"cartesianX", "cartesianY", "cartesianZ"} <= names:
        coordinates, invalid = ["cartesianX", "cartesianY", "cartesianZ"], "cartesianInvalidState"
    elif {"sphericalRange", "sphericalAzimuth", "sphericalElevation"} <= names:
        coordinates, invalid = ["sphericalRange", "sphericalAzimuth", "sphericalElevation"], "sphericalInvalidState"
    else:
        raise ScanFileError(f"{label}: no cartesian or spherical coordinates in its points")
    colours = ["colorRed", "colorGreen", "colorBlue"]
    fields = coordinates + (colours if set(colours) <= names else [])
    fields += [f for f in ("intensity",) if f in names]
    arrays = {f: np.empty(n, dtype=np.float64) for f in fields}
    if invalid in names:
        arrays[invalid] = np.empty(n, dtype=np.int8)
    buffers = libe57.VectorSourceDestBuffer()
    for name, array in arrays.items():
        buffers.append(libe57.SourceDestBuffer(image, name, array, n, True, True))
    reader = points.reader(buffers)
    try:
        got = reader.read()
    finally:
        reader.close()
    if got != n:
        raise ScanFileError(f"{label}: the file holds {got:,} points where its header says {n:,} (truncated?)")

    keep = arrays[invalid] == 0 if invalid in arrays else np.ones(n, dtype=bool)
    a, b, c = (arrays[f][keep] for f in coordinates)
    if invalid == "sphericalInvalidState":
        # E57's spherical convention: azimuth from +X toward +Y, elevation from the XY plane.
        cos_elevation = a * np.cos(c)
        local = np.column_stack([cos_elevation * np.cos(b), cos_elevation * np.sin(b), a * np.sin(c)])
    else:
        local = np.column_stack([a, b, c])

    rotation, translation = np.eye(3), np.zeros(3)
    if scan.isDefined("pose"):
        pose = libe57.StructureNode(scan.get("pose"))
        if pose.isDefined("rotation"):
            q = libe57.StructureNode(pose.get("rotation"))
            rotation = quaternion_matrix(*(_e57_number(q.get(k)) for k in ("w", "x", "y", "z")))
        if pose.isDefined("translation"):
            t = libe57.StructureNode(pose.get("translation"))
            translation = np.array([_e57_number(t.get(k)) for k in ("x", "y", "z")], dtype=np.float64)
    positions = local @ rotation.T + translation
    if not np.all(np.isfinite(positions)):
        raise ScanFileError(f"{label}: coordinates that are not finite numbers")

    colors = None
    if "colorRed" in arrays:
        channels = []
        for name in colours:
            low, high = _e57_field_range(libe57, scan, prototype, name, "colorLimits")
            channels.append(_normalised(arrays[name][keep], low, high))
        colors = srgb_decode(np.column_stack(channels))
    intensities = arrays["intensity"][keep].astype(np.float32) if "intensity" in arrays else None
    metadata = {"format": "e57", "station": index, "coordinates": "spherical" if invalid.startswith("spherical") else "cartesian"}
    name = _e57_string(scan, "name")
    if name:
        metadata["station_name"] = name
    guid = _e57_string(scan, "guid")
    if guid:
        metadata["guid"] = guid
    return ScanArrays(path, positions, colors, intensities, tuple(float(v) for v in translation), metadata)


# ------------------------------------------------------------------------------------- LAS/LAZ


def read_las(path: str) -> ScanArrays:
    """A LAS or LAZ file: integer coordinates times the header's scale plus its offset, in
    double; 16-bit RGB (point formats 2, 3, 5, 7, 8, 10) normalised and decoded from sRGB (files
    that store 8-bit values in the 16-bit fields are recognised by their maximum), intensity as
    stored, the CRS (WKT) recorded in the metadata when the file has one. No scanner position:
    aerial and mobile LiDAR has no single station."""
    laspy = library("laspy", f"{path}: reading LAS/LAZ")
    if path.lower().endswith(".laz"):
        library("lazrs", f"{path}: reading LAZ")
    try:
        with laspy.open(path) as reader:
            header = reader.header
            declared = int(header.point_count)
            data = reader.read()
    except Exception as error:  # laspy raises LaspyException, lazrs its own, OSError, ValueError
        raise ScanFileError(f"{path}: not a readable LAS/LAZ file ({_e57_reason(error)})") from error
    got = len(data.points)
    if got != declared:
        raise ScanFileError(f"{path}: the header says {declared:,} points but the file holds {got:,} (truncated or damaged)")
    scales = np.asarray(header.scales, dtype=np.float64)
    offsets = np.asarray(header.offsets, dtype=np.float64)
    raw = data.points.array
    positions = np.column_stack([raw[axis].astype(np.float64) * scales[i] + offsets[i] for i, axis in enumerate("XYZ")])
    if not np.all(np.isfinite(positions)):
        raise ScanFileError(f"{path}: coordinates that are not finite numbers")
    names = set(data.point_format.dimension_names)
    colors = None
    if {"red", "green", "blue"} <= names:
        rgb = np.column_stack([np.asarray(data[c], dtype=np.float64) for c in ("red", "green", "blue")])
        full = 255.0 if rgb.size and rgb.max() <= 255.0 else 65535.0
        colors = srgb_decode(rgb / full)
    intensities = np.asarray(data["intensity"], dtype=np.float32) if "intensity" in names else None
    metadata = {"format": "laz" if path.lower().endswith(".laz") else "las",
                "point_format": int(data.point_format.id), "scale": scales.tolist(), "offset": offsets.tolist()}
    crs = _las_crs(header)
    if crs:
        metadata["crs"] = crs
    return ScanArrays(path, positions, colors, intensities, None, metadata)


def _las_crs(header) -> Optional[str]:
    """The file's CRS as WKT (its WKT VLR, or what pyproj makes of its GeoTIFF keys), or None."""
    try:
        crs = header.parse_crs()
    except Exception:  # pyproj missing or keys it cannot parse: fall back to the raw WKT record
        crs = None
    if crs is not None:
        try:
            return crs.to_wkt()
        except Exception:
            return str(crs)
    for vlr in list(header.vlrs) + list(getattr(header, "evlrs", None) or []):
        wkt = getattr(vlr, "string", None)
        if type(vlr).__name__ == "WktCoordinateSystemVlr" and wkt:
            return str(wkt).rstrip("\0")
    return None
