"""The decoder table: one valid message of every type decodes; mangled bytes only ever raise ValueError."""

from __future__ import annotations

import numpy as np
import pytest
from msgs_build import samples

from r2d2_viz.msgs.registry import DECODERS, decode
from r2d2_viz.msgs.shapes import Decoded
from r2d2_viz.msgs.typestore import MsgError

SAMPLES = samples()


def test_every_table_type_has_a_sample_and_decodes() -> None:
    assert set(SAMPLES) == set(DECODERS)
    for typename, data in SAMPLES.items():
        out = decode(typename, data)
        items = out.items if isinstance(out, Decoded) else [op.decoded for op in out]
        assert items, typename


def test_unknown_type() -> None:
    with pytest.raises(MsgError, match="no display"):
        decode("geometry_msgs/msg/Vector3", b"\x00\x01\x00\x00")


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("typename", sorted(SAMPLES))
def test_mangled_bytes_raise_only_value_error(typename: str) -> None:
    """Seeded: truncations, flipped bytes and huge length fields (0xFFFFFFF0 / 0x7FFFFFFF written anywhere)."""
    rng = np.random.default_rng(18)
    data = SAMPLES[typename]
    variants = [data[:cut] for cut in range(0, len(data), max(1, len(data) // 40))]
    for _ in range(60):
        b = bytearray(data)
        for i in rng.integers(4, len(b), size=3):
            b[int(i)] = int(rng.integers(0, 256))
        variants.append(bytes(b))
    for pos in range(4, len(data) - 4, 4):
        for word in (b"\xf0\xff\xff\xff", b"\xff\xff\xff\x7f"):
            variants.append(data[:pos] + word + data[pos + 4 :])
    for variant in variants:
        try:
            decode(typename, variant)
        except ValueError:
            pass


def test_the_readme_table_covers_every_decoder_and_is_in_the_readme() -> None:
    from conftest import REPO

    from r2d2_viz.msgs.registry import DECODERS, SHOWN_AS, displays_markdown

    assert sorted(SHOWN_AS) == sorted(DECODERS)  # one row per decoder
    assert displays_markdown() in (REPO / "README.md").read_text()
