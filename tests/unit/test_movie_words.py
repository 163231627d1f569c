"""The words a movie's frame states its magnification in
(``chainrun.plotting.animate``): a number read as a factor, never as part of an
equation beside it (``t = 0``)."""

from __future__ import annotations

import pytest

from chainrun.plotting.animate import _magnified


@pytest.mark.parametrize("factor, words", [
    (200000.0, "magnified 200,000 times"),
    (1000.0, "magnified 1,000 times"),
    (5.0, "magnified 5 times"),
    (2.5, "magnified 2.5 times"),
    (1.0, "true to scale"),
    (0.5, "scaled by 0.5"),
])
def test_a_magnification_is_stated_in_words(factor, words):
    assert _magnified(factor) == words
