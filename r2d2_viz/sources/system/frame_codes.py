"""Frame names as numbers: what ``np.unique(names.astype(str), return_inverse=True)`` gives, without its copy.

``astype(str)`` makes a fixed-width array as wide as the longest name: one 10,000-character frame among 10,000
``/tf`` rows made 20,000 cells of 40 kB each (the ``--tf-tree`` run went from 123 MB to 2.5 GB), and numpy's sort
of it copied it again. Here each row costs one dictionary look-up of the name it already holds (a hash a string
keeps once computed), and only the distinct names are sorted. Pure numpy."""

from __future__ import annotations

from collections.abc import Collection

import numpy as np
import numpy.typing as npt


def frame_codes(
    names: Collection[str] | npt.NDArray[np.object_],
) -> tuple[npt.NDArray[np.object_], npt.NDArray[np.intp]]:
    """The distinct ``names`` sorted (an object array) and each name's index in them, as ``np.unique`` with
    ``return_inverse`` gives them."""
    index: dict[str, int] = {}
    first = np.fromiter((index.setdefault(n, len(index)) for n in names), dtype=np.intp, count=len(names))
    distinct = np.empty(len(index), dtype=object)
    distinct[:] = list(index)
    order = np.argsort(distinct, kind="stable")
    rank = np.empty(len(order), dtype=np.intp)
    rank[order] = np.arange(len(order))
    return distinct[order], rank[first]
