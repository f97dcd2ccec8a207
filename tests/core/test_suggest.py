"""'Did you mean' picks the name an author meant when two are equally similar by letters."""

from __future__ import annotations

from ejsgen._suggest import closest


def test_a_swap_of_two_letters_suggests_the_name_with_those_letters() -> None:
    # 'lable' is as close to 'table' as to 'label' by difflib's ratio; the swap is what a hand types
    assert closest("lable", ["label", "table", "slider"]) == "label"
    assert closest("sldier", ["slider", "folder"]) == "slider"


def test_fewest_edits_win_and_far_names_give_nothing() -> None:
    assert closest("thta", ["theta", "beta"]) == "theta"
    assert closest("omgea", ["omega", "mega"]) == "omega"
    assert closest("zzz", ["theta", "omega"]) is None
