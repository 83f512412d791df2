"""The simulated take written as a camera would record it: a ProRes movie in QuickTime.

:func:`write_movie` encodes the frames of :func:`ocio_vp.simulator.take.write_take` with a
camera log curve (``ARRI LogC3`` by default), converts them to 10-bit Y'CbCr with
colour-science (4:2:2 chroma the mean of each pixel pair, rounded once) and writes ProRes 4444
or 422 HQ with FFmpeg through PyAV, colour-tagged (unless ``tags=False``) with a timecode.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

import numpy as np

from ocio_vp.patterns.sequence import PatternSequence
from ocio_vp.plates.movie import AV_MATRICES, AV_RANGES
from ocio_vp.simulator.take import TakeOptions, render_frames

__all__ = ["MOVIE_CODECS", "MOVIE_ENCODING", "write_movie"]

#: Codec name -> (FFmpeg encoder, profile, pixel format).
MOVIE_CODECS = {
    "prores4444": ("prores_ks", "4", "yuv444p10le"),
    "prores422": ("prores_ks", "3", "yuv422p10le"),
}
#: The camera log curve a simulated movie is in unless told otherwise (the take's encoding).
MOVIE_ENCODING = "ARRI LogC3"
_WEIGHTS = {"rec709": "ITU-R BT.709", "rec2020": "ITU-R BT.2020"}
#: FFmpeg's codes for the tags (AVColorSpace, AVColorRange), as the reader decodes them.
_AV_MATRIX = {name: code for code, name in AV_MATRICES.items()}
_AV_RANGE = {name: code for code, name in AV_RANGES.items()}


def _ycbcr(encoded: np.ndarray, matrix: str, range_: str) -> np.ndarray:
    """10-bit Y'CbCr code values (h, w, 3), not yet rounded, of R'G'B' in [0, 1]."""
    import colour

    normalised = colour.RGB_to_YCbCr(
        np.clip(encoded, 0.0, 1.0),
        K=colour.WEIGHTS_YCBCR[_WEIGHTS[matrix]],
        out_bits=10,
        out_legal=range_ == "legal",
        out_int=False,
    )
    return np.asarray(normalised, dtype=np.float64) * 1023.0


def _frame(ycc: np.ndarray, pix_fmt: str):  # -> av.VideoFrame
    import av

    height, width, _ = ycc.shape
    frame = av.VideoFrame(width, height, pix_fmt)
    for k, plane in enumerate(frame.planes):
        values = ycc[..., k]
        if plane.width != width:  # 4:2:2: each chroma sample the mean of its pixel pair
            values = values.reshape(height, width // 2, 2).mean(axis=2)  # rounded once, below
        stride = plane.line_size // 2
        padded = np.zeros((plane.height, stride), dtype=np.uint16)
        padded[:, : plane.width] = np.clip(np.round(values), 0, 1023).astype(np.uint16)
        plane.update(padded.tobytes())
    return frame


def write_movie(
    sequence: PatternSequence,
    SL: np.ndarray,
    path: str | Path,
    options: TakeOptions | None = None,
    *,
    codec: str = "prores4444",
    encoding: str = MOVIE_ENCODING,
    matrix: str = "rec709",
    range_: str = "legal",
    tags: bool = True,
    timecode: str = "01:00:00:00",
    on_frame: Callable[[], None] | None = None,
) -> Path:
    """Render the take and write it to ``path`` (a ``.mov``); returns ``path``."""
    import av
    import colour

    options = options if options is not None else TakeOptions()
    encoder, profile, pix_fmt = MOVIE_CODECS[codec]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    width, height = options.size
    if width % 2 or height % 2:
        raise ValueError(f"a movie's frame size must be even, got {width}x{height}")
    rate = Fraction(options.fps).limit_denominator(1001)
    with av.open(str(path), "w", format="mov") as container:
        stream = container.add_stream(encoder, rate=rate)
        stream.width, stream.height, stream.pix_fmt = width, height, pix_fmt
        stream.options = {"profile": profile, "vendor": "apl0"}
        stream.metadata["timecode"] = timecode
        if tags:
            ctx = stream.codec_context
            ctx.colorspace, ctx.color_range = _AV_MATRIX[matrix], _AV_RANGE[range_]
            ctx.color_primaries, ctx.color_trc = 1, 1
        for k, image in enumerate(render_frames(sequence, SL, options)):
            encoded = np.asarray(colour.cctf_encoding(np.maximum(image, 0.0), function=encoding))
            frame = _frame(_ycbcr(encoded, matrix, range_), pix_fmt)
            frame.pts = k
            if tags:
                frame.colorspace, frame.color_range = _AV_MATRIX[matrix], _AV_RANGE[range_]
            for packet in stream.encode(frame):
                container.mux(packet)
            if on_frame is not None:
                on_frame()
        for packet in stream.encode():
            container.mux(packet)
    return path
