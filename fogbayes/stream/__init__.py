"""Streaming: compensation and Allan deviation of records larger than memory.

Chunked sources (:mod:`.sources`), the exact record-wide sampling facts (:mod:`.scan`),
bounded-memory Allan accumulators (:mod:`fogbayes.stats.allan_accumulators`, :mod:`.allan`, and the same kernels
in memory in :mod:`fogbayes.stats.allan_blocked`), chunked covariates and 3-sigma flags, compensation into
a file (:mod:`.compensate`, :mod:`.writers`). Results equal the in-memory paths.
"""

from .allan import StreamAllan, stream_allan
from .compensate import StreamCompensation, compensate_stream
from ..stats.allan_blocked import allan_variance_fast, oadev_fast
from .scan import TimeScan, scan_time
from .sources import Chunk, RecordSource, open_source

__all__ = ["Chunk", "RecordSource", "StreamAllan", "StreamCompensation", "TimeScan",
           "allan_variance_fast", "compensate_stream", "oadev_fast", "open_source",
           "scan_time", "stream_allan"]
