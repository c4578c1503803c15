"""PNG ↔ numpy conversions (the ``numpy`` extra: numpy and Pillow)."""

from __future__ import annotations

import io
from typing import Any


def _imports() -> tuple[Any, Any]:
    try:
        import numpy as np
        from PIL import Image  # type: ignore[import-not-found, unused-ignore]
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise ImportError("images as arrays need numpy and Pillow: pip install 'winged-client[numpy]'") from exc
    return np, Image


def png_to_array(data: bytes) -> Any:
    """A PNG as a numpy array.

    8-bit RGB images give ``H×W×3`` ``uint8`` arrays, RGBA ``H×W×4``, 8-bit grey ``H×W``
    ``uint8``, and 16-bit grey (``depth`` and ``ids`` images) ``H×W`` ``uint16``.
    """
    np, image_module = _imports()
    with image_module.open(io.BytesIO(data)) as image:
        image.load()
        mode = image.mode
        if mode.startswith("I;16"):
            return np.asarray(image).astype(np.uint16)
        if mode == "I":
            return np.asarray(image).astype(np.uint16)
        if mode == "P":
            image = image.convert("RGBA" if "transparency" in image.info else "RGB")
        elif mode == "1":
            image = image.convert("L")
        return np.asarray(image).copy()


def array_to_png(array: Any) -> bytes:
    """A numpy array as PNG bytes: ``bool`` and ``uint8`` 2-D as 8-bit grey (``True`` as
    255), ``uint16`` 2-D as 16-bit grey, ``H×W×3`` as RGB and ``H×W×4`` as RGBA."""
    np, image_module = _imports()
    a = np.asarray(array)
    if a.dtype == np.bool_:
        a = a.astype(np.uint8) * 255
    if a.ndim == 2 and a.dtype == np.uint16:
        image = image_module.fromarray(a)
    elif a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4)):
        image = image_module.fromarray(a.astype(np.uint8))
    else:
        raise ValueError(f"cannot encode an array of shape {a.shape} as a PNG")
    out = io.BytesIO()
    image.save(out, format="PNG")
    return out.getvalue()
