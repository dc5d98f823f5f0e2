"""The verdict: is a written tile seamless, at its wrap and inside, and faithful to its source?

One detector (:mod:`.classifier` over :mod:`.features`, read along every line by :mod:`.lines`; for a
texture judged against itself, also the line breaks of :mod:`.breaks`) and one fidelity rule
(:mod:`.tolerance`) decide ``passed`` everywhere: the process status and exit code, the report, the USD
provenance, ``seamless-usd check`` and the scan's ``already-tileable`` intent, which judge a texture on its
own from one reading of its files (:mod:`.alone`). See :mod:`.judge` for exactly what ``passed`` means. What
a verdict reads is prepared once (:mod:`.reference`) and passed down to every candidate and figure read
against the same source.
"""
from __future__ import annotations

from .alone import FileMap, judge_alone
from .judge import LENGTH, SEAM_MARGIN, SELF_MARGIN, STEP, Verdict, judge, judge_reading
from .lines import Seam
from .prepare import WORK_SIDE
from .reference import Reading, Reference
from .tolerance import FIDELITY_KEYS, faithfulness, scale_tolerance

__all__ = ["Verdict", "Seam", "judge", "judge_reading", "judge_alone", "FileMap", "Reference", "Reading", "faithfulness", "scale_tolerance",
           "FIDELITY_KEYS", "SEAM_MARGIN", "SELF_MARGIN", "LENGTH", "STEP", "WORK_SIDE"]
