"""What a frame costs each session: an image's source (a virtual camera's render, the costliest
thing a frame computes) is read only when its picture may be sent, not every frame."""

from __future__ import annotations

from ejsrl.view.elements import Dynamic


def test_an_image_source_is_read_only_when_its_picture_may_be_sent(served):
    image = served.view.panel.images[0]
    reads = []
    source = image.image.source
    image.image.source = Dynamic(lambda m: reads.append(1) or source(m), "counted")
    from ejsrl.view._plots import IMAGE_SETTLE

    served.clock.advance(IMAGE_SETTLE)  # the element is shown (and sent pictures) IMAGE_SETTLE after it is made
    served.app.play()
    for _ in range(30):  # one second at 30 frames/s; pictures go at most 20 times a second
        served.clock.advance(1.0 / 30.0)
        served.app.frame()
    assert image.handle.visible  # made with its first picture (sent again only when it changes)
    assert 10 <= len(reads) <= 20, len(reads)  # was 30: one render per frame
