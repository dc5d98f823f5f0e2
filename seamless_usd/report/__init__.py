"""Run reports: the model (JSON form with a schema in ``schemas/``) and the HTML page."""
from seamless_usd.report.model import MapReport, Previews, Report, StackReport, StackStatus

__all__ = ["MapReport", "Previews", "Report", "StackReport", "StackStatus"]
