"""What an image element's source may give (session 11's trial): a vision pipeline's result
shows as its picture with the features it found drawn over it; a value that is no picture
pauses the lab with a message saying what it gives (the element stayed blank, silently)."""

from __future__ import annotations

import numpy as np

from ejsrl import vision
from ejsrl.view._image import prepare_image
from ejsrl.view._plots import IMAGE_SETTLE
from ejsrl.view.elements import Dynamic


def _frames(served, n: int = 5) -> None:
    served.clock.advance(IMAGE_SETTLE)
    for _ in range(n):
        served.clock.advance(0.1)
        served.app.frame()


def test_a_pipeline_result_shows_its_image_and_points(served):
    image = served.view.panel.images[0]
    pic = np.zeros((60, 80, 3), np.uint8)
    pic[20:45, 25:60] = 220  # a bright box: four corners
    result = vision.Pipeline("gray", ("susan", {"max_corners": 4}))(pic)
    assert len(result.points) == 4
    image.image.source = Dynamic(lambda m: result, "the pipeline")
    image.image.points = None
    _frames(served)
    assert served.app.error is None
    assert np.array_equal(image.handle.image, prepare_image(result.image, result.points))


def test_a_source_that_is_no_picture_pauses_the_lab_saying_what_it_gives(served):
    image = served.view.panel.images[0]
    image.image.source = Dynamic(lambda m: np.zeros(5), "a vector")
    served.app.play()
    _frames(served)
    err = served.app.error
    assert err is not None and not served.app.is_playing()
    text = str(err)
    assert "not a picture" in text and "(5,)" in text and ".image" in text, text
    served.app.frame()  # and the app goes on serving



def test_a_number_or_a_string_is_said_in_plain_words(served):
    from ejsrl.view._image import picture_of

    for value, said in ((3.5, "a single number (3.5)"), ("hello", "a str ('hello')"), ([1, [2]], "a list")):
        try:
            picture_of(value, None, "Cam")
        except TypeError as e:
            assert f"image element 'Cam': its source gives {said}, not a picture" in str(e), str(e)
        else:
            raise AssertionError(value)
