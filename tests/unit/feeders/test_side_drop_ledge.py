"""A side drop as a ledge for boxes: a crosswise box falls only when its centre of mass lies
past the edge, and on a floor tilted towards the wall that centre leans (T/2) tan(tilt) nearer
the wall than its footprint's. A drop that keeps crosswise boxes runs, but is warned of, naming
its key and the bound; by hand for the orientation demo's 1.0 x 0.5 x 0.35 mm box."""

import math
import warnings

import pytest

from helpers import REPO, vibrofeed
from vibrofeed.decks import Deck
from vibrofeed.feeders.linear import SideDropWarning
from vibrofeed.parameters import resolve

L, W, T = 1e-3, 5e-4, 3.5e-4


def checked(width: float, tilt: float) -> list[warnings.WarningMessage]:
    """The side-drop warnings of the demo's line with section 2's drop ``width`` [m] on a floor
    tilted ``tilt`` [deg] towards the wall (both sections: the joint between them stays sound)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # (resolve checks the feeder as a whole)
        resolve(Deck.find(REPO / "feeders" / "orient_line.toml"),
                {"element.2.side_drop.width": repr(width), "element.1.cross_tilt": repr(tilt),
                 "element.2.cross_tilt": repr(tilt)})
    return [w for w in caught if issubclass(w.category, SideDropWarning)]


def held(tilt: float) -> float:
    """A crosswise box's centre of mass from the wall, by hand: L/2 less (T/2) tan(tilt)."""
    return L / 2 - T / 2 * math.tan(math.radians(tilt))


def test_the_bound_by_hand():
    assert held(15) == pytest.approx(4.531e-4, abs=1e-7)  # the demo's tilt
    assert held(0) == L / 2


@pytest.mark.parametrize("tilt", [15.0, 0.0, 5.0])
def test_a_drop_narrower_than_the_leaning_centre_is_quiet_and_one_as_wide_is_warned_of(tilt):
    bound = held(tilt)
    assert checked(bound - 1e-6, tilt) == []
    (warning,) = checked(bound, tilt)
    (wider,) = checked(bound + 1e-6, tilt)
    text = str(warning.message)
    assert text.startswith(f"element.2.side_drop.width={bound:g} m: a box lying crosswise against the wall "
                           f"has its centre of mass {bound:.3g} m out")  # in the name the user gave
    assert "keeps crosswise boxes" in str(wider.message)


def test_the_demos_drop_drops_crosswise_boxes_by_three_microns():
    """0.45 mm on the 15 degree floor: quiet; 0.46 mm, inside L/2 but past the leaning centre
    of mass: warned of (a check by the footprint alone, L/2 = 0.5 mm, would pass it)."""
    assert checked(4.5e-4, 15.0) == []
    assert len(checked(4.6e-4, 15.0)) == 1
    assert 4.6e-4 < L / 2 and held(15) - 4.5e-4 == pytest.approx(3.1e-6, abs=1e-7)


def test_prepare_says_the_warning_once_in_the_users_name(tmp_path):
    """The check runs as the values are resolved and again as the deck is prepared; the user
    hears it once, as the name they gave (it was said twice, the second time as s2_drop_width)."""
    proc = vibrofeed("prepare", REPO / "feeders" / "orient_line.toml",
                     "-p", "element.2.side_drop.width=4.6e-4", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    said = [line for line in proc.stderr.splitlines() if line.startswith("vibrofeed: warning:")]
    assert len(said) == 1, said
    assert said[0].startswith("vibrofeed: warning: element.2.side_drop.width=0.00046 m: a box lying "
                              "crosswise")
