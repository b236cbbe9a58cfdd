"""``ppfab.frame.Frame``: its normal is ``np.cross`` of its axes bit for bit (the writers' files depend on it)."""

import numpy as np

from ppfab.frame import Frame


def test_the_normal_is_numpys_cross_product_bit_for_bit():
    rng = np.random.default_rng(11)
    ex = rng.normal(size=(20_000, 3)) * 10.0 ** rng.uniform(-6, 6, size=(20_000, 3))
    ey = rng.normal(size=(20_000, 3)) * 10.0 ** rng.uniform(-6, 6, size=(20_000, 3))
    ex[:100] = np.eye(3)[rng.integers(0, 3, 100)]                  # axis-aligned frames: exact zeros and signs
    ey[:100] = -np.eye(3)[rng.integers(0, 3, 100)]
    ours = np.array([Frame(np.zeros(3), a, b).normal for a, b in zip(ex, ey)])
    assert ours.dtype == np.float64 and ours.shape == (20_000, 3)
    assert np.array_equal(ours.view(np.int64), np.cross(ex, ey).view(np.int64))   # the same bits, -0.0 included
