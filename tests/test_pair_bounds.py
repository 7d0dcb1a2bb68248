"""Each pair's kept bounds per slot: slots made in one pass start as made one at a time.

Truth here: the same store made one slot after the other (the rule that defines where a new
slot starts: from the nearest slot kept then), on random slots and bounds, including the
patterns of the dense check (a fresh store, then the middles of its intervals) and batches
where a new slot lies nearer another new one (made one at a time).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from freefloat.robot.motion_bound import PairBounds


def _state(bounds: PairBounds, slots: list[float]) -> list[tuple[np.ndarray, ...]]:
    """Per slot: its bounds, and its joints where a bound is kept."""
    out = []
    for slot in slots:
        row = bounds._rows[slot]
        kept = ~np.isnan(bounds._lower[row])
        out.append((bounds._lower[row], bounds._upper[row], bounds._joints[row][kept]))
    return out


def _equal(a: list[tuple[np.ndarray, ...]], b: list[tuple[np.ndarray, ...]]) -> bool:
    flat = [(x, y) for p, q in zip(a, b, strict=True) for x, y in zip(p, q, strict=True)]
    return all(np.array_equal(x, y, equal_nan=True) for x, y in flat)


@pytest.mark.parametrize("seed", range(12))
def test_slots_made_in_one_pass_start_as_made_one_at_a_time(seed):
    rng = np.random.default_rng(seed)
    pairs, joints = 6, 3
    weights = rng.uniform(0.1, 1.0, (pairs, joints))
    batched, single = PairBounds(weights), PairBounds(weights)
    kept = sorted(set(np.round(rng.uniform(0, 1, rng.integers(0, 6)), 3).tolist()))
    for store in (batched, single):  # the same slots kept before, with bounds
        for k, slot in enumerate(kept):
            q, low = np.full(joints, float(k)), np.full(pairs, k - 1.0)
            store.record(slot, np.arange(pairs), q, low, low + 2.0)
    if seed % 3 == 0:  # the middles of the kept slots' intervals: the dense check's halving
        new = [0.5 * (a + b) for a, b in itertools.pairwise(kept)] or [0.25, 0.75]
    else:
        new = np.round(rng.uniform(0, 1, 7), 3).tolist()
    asked = new + kept[:1] + new[:2]  # kept slots and repeats among them
    rows_batched = batched._rows_of(asked)
    rows_single = [single._row(slot) for slot in asked]
    assert len(rows_batched) == len(asked)
    assert [batched._rows[s] for s in asked] == rows_batched
    assert [single._rows[s] for s in asked] == rows_single
    every = sorted(set(asked) | set(kept))
    assert _equal(_state(batched, every), _state(single, every))
    assert batched._keys == single._keys and batched._recent == single._recent


def test_a_new_slot_nearer_another_new_one_is_made_after_it():
    """Kept 0 and 1; new 0.6 then 0.5: made one at a time, 0.5 starts from 0.6 (which
    started from 1), not from 0 (as near as 1) — and so it does when asked together."""
    weights = np.ones((2, 1))
    batched, single = PairBounds(weights), PairBounds(weights)
    for store in (batched, single):
        store.record(0.0, np.arange(2), np.zeros(1), np.zeros(2), np.ones(2))
        store.record(1.0, np.arange(2), np.ones(1), np.full(2, 5.0), np.full(2, 6.0))
    batched._rows_of([0.6, 0.5])
    for slot in (0.6, 0.5):
        single._row(slot)
    assert batched._lower[batched._rows[0.5]].tolist() == [5.0, 5.0]
    assert _equal(_state(batched, [0.6, 0.5]), _state(single, [0.6, 0.5]))


def test_the_store_grows_and_keeps_its_rows():
    """More slots than the arrays first hold: every slot's bounds are kept as recorded."""
    weights = np.ones((3, 2))
    store = PairBounds(weights)
    slots = np.linspace(0.0, 1.0, 3 * PairBounds.ROWS + 5).tolist()
    for k, slot in enumerate(slots):
        store.record(slot, np.arange(3), np.full(2, k), np.full(3, -k), np.full(3, k))
    for k, slot in enumerate(slots):
        row = store._rows[slot]
        assert store._lower[row].tolist() == [-k] * 3
        assert store._joints[row].tolist() == [[k, k]] * 3


def test_the_dense_checks_patterns_are_made_in_one_pass():
    """A fresh store's first batch and the middles of kept intervals are made in one pass
    (and start as made one at a time: the tests above); a new slot nearer another new one is
    not."""
    weights = np.ones((2, 1))
    fresh = PairBounds(weights)
    slots = [0.0, 0.25, 0.5, 0.75, 1.0]
    assert fresh._made_at_once(slots, [None] * len(slots))
    kept = PairBounds(weights)
    for slot in slots:
        kept.record(slot, np.arange(2), np.zeros(1), np.zeros(2), np.ones(2))
    middles = [0.125, 0.375, 0.625, 0.875]
    assert kept._made_at_once(middles, [None] * len(middles))
    assert not kept._made_at_once([0.6, 0.59], [None, None])
