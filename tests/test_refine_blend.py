"""What the refinement makes at a copied tile's joins besides copies: gradient-domain blending of a band
around them (``RefineConfig.blend``) and Kwatra's robust vote (``RefineConfig.robust_vote``)."""
from __future__ import annotations

import numpy as np
import pytest

from seamless_usd.synthesis.refinement.blend import band_mask, blend_band, join_edges
from seamless_usd.verdict.joins import join_stats

from benchscripts import load_benchmark

synthetic = load_benchmark("synthetic")


def _two_blocks(rows: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """A source black on the left, white on the right; a 16-wide tile whose columns 0-7 copy a black stretch
    and 8-15 a white one: joins before column 8 and at the wrap (before column 0), and a row join at the
    wrap (rows copy 5..5+rows-1)."""
    source = np.zeros((40, 40, 1), np.float32)
    source[:, 20:] = 1.0
    field = np.zeros((rows, 16, 2), np.int64)
    field[..., 0] = np.arange(rows)[:, None] + 5
    field[:, :8, 1] = np.arange(8)[None, :] + 2
    field[:, 8:, 1] = np.arange(8)[None, :] + 25
    return source, field


def test_the_joins_and_the_band_are_where_the_copies_meet():
    _, field = _two_blocks()
    across_rows, across_columns = join_edges(field)
    assert sorted(set(np.nonzero(across_columns)[1])) == [0, 8]  # the lines before columns 0 and 8
    assert sorted(set(np.nonzero(across_rows)[0])) == [0]  # the wrap between the last row and the first
    band = band_mask([across_rows, across_columns], 3)
    # both texels of a joined pair, grown by 2: columns 5-10 and 13-2 (round the wrap), rows 5-2
    assert sorted(set(np.nonzero(~band.any(axis=0))[0])) == []  # every column meets a row join band
    middle = band[3]  # a row away from the row join
    assert sorted(np.nonzero(middle)[0]) == [0, 1, 2, 5, 6, 7, 8, 9, 10, 13, 14, 15]
    assert band_mask([across_rows, across_columns], 0).sum() == 0


def _least_squares(tile: np.ndarray, band: np.ndarray, wanted=lambda a, b: 0.0) -> np.ndarray:
    """Independent reference: the band's values minimising, over every neighbour pair (a, b) on the torus
    that touches the band, the sum of (x_b - x_a - wanted(a, b))^2, the others held, by dense lstsq."""
    h, w = band.shape
    unknown = {p: i for i, p in enumerate(zip(*np.nonzero(band)))}
    rows, rhs = [], []
    for y in range(h):
        for x in range(w):
            for b in (((y + 1) % h, x), (y, (x + 1) % w)):
                a = (y, x)
                if a not in unknown and b not in unknown:
                    continue
                row = np.zeros(len(unknown))
                value = wanted(a, b)
                for q, sign in ((b, 1.0), (a, -1.0)):
                    if q in unknown:
                        row[unknown[q]] += sign
                    else:
                        value -= sign * float(tile[q])
                rows.append(row)
                rhs.append(value)
    solution = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]
    out = tile.astype(np.float64).copy()
    for (y, x), i in unknown.items():
        out[y, x] = solution[i]
    return out


def test_a_step_between_two_flat_blocks_is_spread_over_the_band():
    """The source is flat on both sides of each join, so every difference the source asks for is 0: inside
    the band the tile is the least-squares smoothest fill between the copies held around it (checked
    against a dense solve of that definition), a ramp from black to white across the join, and outside
    the band every texel is the copy it was."""
    source, field = _two_blocks()
    (tile,), band = blend_band([source], field, 3)
    copied = source[field[..., 0], field[..., 1]]
    reference = _least_squares(copied[..., 0], band)
    assert np.allclose(tile[..., 0], reference, atol=2e-3)
    assert np.array_equal(tile[~band], copied[~band])
    middle = tile[4, :, 0]  # away from the row join at the wrap
    assert np.all(np.diff(middle[4:12]) > 0.02)  # up from black to white across the join before column 8
    assert np.all(np.diff(middle[[12, 13, 14, 15, 0, 1, 2, 3]]) < -0.02)  # and down again round the wrap
    assert middle[4] == 0.0 and middle[11] == 1.0  # the band ends on the copies


def test_inside_the_band_each_step_is_the_one_the_source_takes():
    """A source that brightens faster and faster to the right (x^2): across every pair the band asks for the
    mean of the step each side's source takes there (worked out pair by pair here, and solved densely), so
    the blocks' own gradients carry on into the band and the join's jump is shared out over it."""
    source = np.tile(((np.arange(40, dtype=np.float32) / 40) ** 2)[None, :, None], (40, 1, 1))
    _, field = _two_blocks()

    def wanted(a, b) -> float:
        if a[0] != b[0]:
            return 0.0  # the source does not change down a column
        (ya, xa), (yb, xb) = field[a], field[b]
        ahead = source[ya, xa + 1, 0] - source[ya, xa, 0]  # what follows a's origin
        behind = source[yb, xb, 0] - source[yb, xb - 1, 0]  # what precedes b's origin
        return float(ahead + behind) / 2

    (tile,), band = blend_band([source], field, 3)
    copied = source[field[..., 0], field[..., 1]]
    reference = _least_squares(copied[..., 0], band, wanted)
    assert np.allclose(tile[..., 0], reference, atol=2e-3)
    assert not np.allclose(reference, _least_squares(copied[..., 0], band), atol=2e-3)  # the gradients count
    assert np.all(np.diff(tile[4, 4:12, 0]) > 0)  # climbing across the join before column 8


def test_normals_are_blended_as_vectors_and_stay_unit_length_with_every_map_on_one_band():
    source, field = _two_blocks()
    tilt = np.array([0.6, 0.0, 0.8], np.float32)
    normal = np.where(source > 0.5, tilt, np.array([0.0, 0.0, 1.0], np.float32))
    (colour, blended), band = blend_band([source, normal], field, 3, normals=[False, True])
    length = np.linalg.norm(blended, axis=-1)
    assert np.allclose(length, 1.0, atol=1e-5)
    copied = normal[field[..., 0], field[..., 1]]
    assert np.array_equal(blended[~band], copied[~band])
    moved = np.abs(blended - copied).max(axis=-1) > 1e-6
    assert moved.any() and not (moved & ~band).any()  # one band for every map
    assert np.abs(colour - source[field[..., 0], field[..., 1]]).max(axis=-1)[~band].max() == 0


def test_a_tile_without_joins_is_its_copy():
    source, _ = _two_blocks()
    field = np.stack(np.meshgrid(np.arange(4, 20), np.arange(3, 19), indexing="ij"), -1)
    (tile,), band = blend_band([source], field, 3)
    # the only joins are at the wrap (a window is not periodic): the band is there, nowhere else
    assert band[8, 8] == False  # noqa: E712
    assert np.array_equal(tile[~band], source[field[..., 0], field[..., 1]][~band])


@pytest.mark.usefixtures("one_thread")
def test_blending_a_refined_stone_tile_leaves_fewer_bad_joins_and_keeps_the_stones():
    """Through ``refine``: the same field with and without the band; the blended tile has fewer bad joins
    (read through the field, where the blended texels stand), the copies outside the band are untouched,
    and the stones' scale stays the source's."""
    from seamless_usd.metrics import scale_ratio
    from seamless_usd.synthesis import RefineConfig, refine

    stack = synthetic.cells(160, 32, seed=5)
    names = list(stack)
    maps = [stack[k][0] for k in names]
    normals = [stack[k][1] for k in names]
    plain = refine(maps, None, (128, 128), RefineConfig(lattice=False, coarsest=32), seed=0, normals=normals)
    blended = refine(maps, None, (128, 128), RefineConfig(lattice=False, coarsest=32, blend=3), seed=0,
                     normals=normals)
    assert np.array_equal(plain.field, blended.field) and plain.band is None
    band = blended.band
    assert 0.05 < band.mean() < 0.8
    for a, b in zip(plain.maps, blended.maps):
        assert np.array_equal(a[~band], b[~band])
    before = join_stats(plain.maps, maps, normals, names, origin=plain.field)["maps"]["stack"]["count"]
    after = join_stats(blended.maps, maps, normals, names, origin=blended.field)["maps"]["stack"]["count"]
    assert after < 0.6 * before, (before, after)
    for tile, source, normal in zip(blended.maps, maps, normals):
        assert 0.8 < scale_ratio(tile, source, normal) < 1.25


def _as_tensor(img: np.ndarray):
    import torch

    return torch.from_numpy(np.ascontiguousarray(img.transpose(2, 0, 1)))


def test_the_robust_vote_keeps_coherent_copies_and_lets_the_majority_side_win_at_a_join():
    """Inside a block every overlapping patch copies the same texel: the vote is that texel. At the join of
    a black and a white block, a texel two columns inside the black block is covered by more patches
    copying black than white: the robust vote stays near black where the mean vote goes grey."""
    import torch

    from seamless_usd.synthesis.refinement.patches import robust_vote, vote

    rng = np.random.default_rng(1)
    source = np.zeros((40, 40, 1), np.float32)
    source[:, 20:] = 1.0
    source += rng.normal(0, 0.02, source.shape).astype(np.float32)  # grain, so copies are told apart
    _, field = _two_blocks(rows=16)
    fld = torch.from_numpy(field)
    robust = robust_vote(_as_tensor(source), fld, r=3).numpy()[0]
    mean = vote(_as_tensor(source), fld, r=3).numpy()[0]
    copied = source[field[..., 0], field[..., 1], 0]
    assert np.allclose(robust[8, 3:5], copied[8, 3:5], atol=1e-5)  # 3+ columns from every join: the copy
    assert np.allclose(robust[8, 11:13], copied[8, 11:13], atol=1e-5)
    for column, side in ((6, 0.0), (9, 1.0)):  # two columns inside the black block, one inside the white
        assert abs(robust[8, column] - side) < 0.1, (column, robust[8, column])
        assert abs(mean[8, column] - side) > 0.2, (column, mean[8, column])


@pytest.mark.usefixtures("one_thread")
def test_the_robust_vote_through_refine_keeps_maps_aligned_and_normals_unit_length():
    from seamless_usd.synthesis import RefineConfig, refine

    rng = np.random.default_rng(2)
    colour = rng.uniform(-1, 1, (96, 96, 3)).astype(np.float32)
    normal = np.concatenate([rng.normal(0, 0.3, (96, 96, 2)), np.ones((96, 96, 1))], -1).astype(np.float32)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    twin = colour.copy()
    result = refine([colour, twin, normal], None, (64, 64), RefineConfig(lattice=False, coarsest=32, robust_vote=2),
                    seed=0, normals=[False, False, True])
    voted, voted_twin, voted_normal = result.maps
    assert np.array_equal(voted, voted_twin)  # one set of weights for every map
    assert np.allclose(np.linalg.norm(voted_normal, axis=-1), 1.0, atol=1e-5)
    fy, fx = result.field[..., 0], result.field[..., 1]
    same = np.all(voted == colour[fy, fx], axis=-1)
    assert 0.05 < same.mean() < 1.0  # exact copies inside the blocks, voted values at the joins
    assert np.array_equal(voted_normal[same], normal[fy, fx][same])  # the same texels of every map
