"""Core's messages worded for people inside FreeCAD: no command-line flags, no float noise."""
from workcal_wb.core.result import CalibrationResult, Reason
from workcal_wb.core.wording import for_people


def test_flags_in_brackets_go_and_flags_in_sentences_become_words():
    assert for_people("the scan shows too little of the workpiece model (use --regions auto)") == \
        "the scan shows too little of the workpiece model"
    assert for_people("refused; export anyway (--force)") == "refused; export anyway"
    assert for_people("read it again with --model-units m") == "read it again with unit m"
    assert for_people("or give --path-reach 40") == "or give path reach 40"


def test_float_noise_is_rounded_and_plain_numbers_stay():
    assert for_people("explained 70.96000000000001 % of 0.3 mm") == "explained 70.96 % of 0.3 mm"


def test_a_calibration_summary_worded_for_the_report_view_has_no_flags():
    result = CalibrationResult(status="failed", W=None, reasons=[Reason("not_found", "too little of it (use --regions auto)")])
    assert "--" in result.summary() and "--" not in for_people(result.summary())
