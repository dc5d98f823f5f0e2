"""A sublayer or reference that cannot be opened is reported once as a ``composition-error`` finding, under whichever
variant selection it is found, and USD's own printout of it is not repeated on the terminal (it was a raw
``Warning: in _ReportErrors at line ... of stage.cpp`` beside the finding)."""
from __future__ import annotations

import json

from seamless_usd_cli.main import main

STAGE = """#usda 1.0
(
    defaultPrim = "Root"
    subLayers = [@./missing_sublayer.usda@]
)

def Xform "Root" (
    variants = {
        string look = "plain"
    }
    prepend variantSets = "look"
)
{
    variantSet "look" = {
        "plain" {
        }
        "dressed" {
            def "Dressing" (
                prepend references = @./missing_dressing.usda@
            )
            {
            }
        }
    }
}
"""


def test_composition_errors_are_findings_once_each_and_not_printed_again(tmp_path, capfd):
    scene = tmp_path / "scene.usda"
    scene.write_text(STAGE)
    assert main(["scan", str(scene), "--json"]) == 0
    out, err = capfd.readouterr()
    found = [f for f in json.loads(out)["findings"] if f["code"] == "composition-error"]
    messages = [f["message"] for f in found]
    assert sum("missing_sublayer.usda" in m for m in messages) == 1, messages
    [dressing] = [f for f in found if "missing_dressing.usda" in f["message"]]  # only under the other selection
    assert "(in look=dressed)" in dressing["message"], dressing
    # named by the prim whose reference failed, saying what to do (it named the stage, with USD's words alone)
    assert dressing["where"] == "</Root/Dressing>" and "restore the file or fix" in dressing["message"]
    assert "_ReportErrors" not in err and "Warning: in" not in err, err
