"""CLF text that does not depend on the OpenColorIO version that wrote it.

OCIO's CLF writer marks its ``ProcessList`` with no namespace up to 2.5 and with SMPTE ST
2136-1's from 2.6, which some readers (``colour-clf-io``) refuse. Every CLF this package writes
gets the Academy CLF v3 header instead; the nodes OCIO writes are all CLF v3 nodes.
"""

from __future__ import annotations

import hashlib
import re

__all__ = ["CLF_FORMAT", "CLF_V3_NAMESPACE", "clf_v3", "sidecar_name"]

CLF_FORMAT = "Academy/ASC Common LUT Format"
CLF_V3_NAMESPACE = "urn:AMPAS:CLF:v3.0"

_PROCESS_LIST = re.compile(r"<ProcessList\b([^>]*)>")
_NAMESPACE = re.compile(r"\s+xmlns(:\w+)?\s*=\s*\"[^\"]*\"")
_VERSION = re.compile(r"\s+compCLFversion\s*=\s*\"[^\"]*\"")


def clf_v3(text: str) -> str:
    """``text`` (a CLF document) with an Academy CLF v3 ``ProcessList`` header.

    Examples
    --------
    >>> clf_v3('<ProcessList compCLFversion="3" xmlns="http://www.smpte-ra.org/ns/2136-1/2024"'
    ...        ' id="a">')
    '<ProcessList xmlns="urn:AMPAS:CLF:v3.0" compCLFversion="3.0" id="a">'
    """
    match = _PROCESS_LIST.search(text)
    if match is None:
        raise ValueError("not a CLF document: no <ProcessList> element")
    attributes = _VERSION.sub("", _NAMESPACE.sub("", match.group(1)))
    header = f'<ProcessList xmlns="{CLF_V3_NAMESPACE}" compCLFversion="3.0"{attributes}>'
    return text[: match.start()] + header + text[match.end() :]


def sidecar_name(stem: str, text: str) -> str:
    """``<stem>_<hash>.clf``: OCIO caches files by path for the whole process, so sidecars
    that differ must not share a name."""
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:12]
    return f"{stem}_{digest}.clf"
