"""The detector error breakdown equals a hand count on a constructed frame."""

from sortbot.eval.detector_errors import ErrorConfig, match_frame
from sortbot.perception.detection import Detection

FORK, KNIFE, SPOON = 0, 1, 2


def test_each_object_and_detection_lands_in_the_right_bucket():
    truth = [(FORK, (0, 0, 100, 20)), (KNIFE, (200, 0, 300, 20)), (SPOON, (0, 100, 100, 140)), (FORK, (300, 300, 400, 320))]
    detections = [
        Detection((0, 0, 100, 20), 0.9, "fork"),  # found, right class
        Detection((201, 0, 300, 20), 0.8, "spoon"),  # found, but called a spoon
        Detection((2, 0, 100, 20), 0.7, "fork"),  # a second box on the first fork
        Detection((60, 100, 160, 140), 0.6, "spoon"),  # IoU 40/160 = 0.25 with the spoon: seen, poorly boxed
        Detection((500, 400, 540, 440), 0.5, "knife"),  # nothing there
    ]  # and nothing on the second fork: missed
    result = match_frame(truth, detections, ErrorConfig())
    assert result == {"correct": 1, "wrong_class": [("knife", "spoon")], "poor_box": 1, "missed": 1,
                      "false_positive": 1, "duplicate": 1}


def test_the_more_confident_detection_claims_an_object_first():
    truth = [(KNIFE, (0, 0, 100, 20))]
    detections = [Detection((0, 0, 100, 20), 0.4, "knife"), Detection((1, 0, 100, 20), 0.9, "fork")]
    result = match_frame(truth, detections, ErrorConfig())
    assert result["wrong_class"] == [("knife", "fork")] and result["duplicate"] == 1 and result["correct"] == 0


def test_an_empty_frame_has_only_false_positives():
    result = match_frame([], [Detection((0, 0, 10, 10), 0.9, "fork")], ErrorConfig())
    assert result["false_positive"] == 1 and result["correct"] == result["missed"] == 0
