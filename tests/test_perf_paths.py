"""The shortcuts of the hot user paths give what the long way gives, bit for bit."""

import numpy as np
import pytest

from gsfric import _threads, models
from gsfric.signal import windows


def _signals():
    rng = np.random.default_rng(7)
    t = np.arange(3000) / 500.0
    chirp = np.sin(2 * np.pi * (0.1 * t + 0.2 * t ** 2))[:, None] * [0.01, 0.02, 0.03]
    moves = models.point_to_point(np.random.default_rng(2), 3000).position
    return {
        "noisy chirp": chirp + rng.normal(0.0, 1e-5, chirp.shape),
        "moves and rests, noisy": moves + rng.normal(0.0, 2e-6, moves.shape),
        "moves and rests, exact": moves,
        "short": chirp[:200] + rng.normal(0.0, 1e-4, (200, 3)),
    }


@pytest.mark.parametrize("name", list(_signals()))
@pytest.mark.parametrize("deriv", [1, 2])
def test_window_choice_stops_only_where_no_longer_window_can_win(monkeypatch, name, deriv):
    y = _signals()[name]
    orders, chosen = windows.adaptive_filters(y, deriv=deriv)
    monkeypatch.setattr(windows, "_settled", lambda *args: False)   # every candidate window
    every_orders, every_windows = windows.adaptive_filters(y, deriv=deriv)
    np.testing.assert_array_equal(orders, every_orders)
    np.testing.assert_array_equal(chosen, every_windows)


def test_filter_pairs_are_the_sorted_distinct_rows():
    rng = np.random.default_rng(3)
    for n in (1, 7, 5000):
        orders = rng.choice([4, 6], n)
        chosen = rng.choice([5, 7, 9, 13, 21, 1423], n)
        expected = np.unique(np.stack([orders, chosen], axis=1), axis=0)
        np.testing.assert_array_equal(windows.filter_pairs(orders, chosen), expected)


def test_in_parallel_keeps_order_context_and_errors():
    def divide():
        return np.float64(1.0) / np.float64(0.0)

    with np.errstate(divide="raise"):
        with pytest.raises(FloatingPointError):
            _threads.in_parallel(lambda: 1, divide)       # the caller's errstate holds there
    with np.errstate(divide="ignore"):
        assert _threads.in_parallel(lambda: "a", divide, lambda: "c") == ["a", np.inf, "c"]
    with pytest.raises(ZeroDivisionError):
        _threads.in_parallel(lambda: 1, lambda: 1 / 0)
