"""Where a render puts each pixel's samples among its kernel's lanes, so that no pixel is summed
by two threads and the pixel sums are the same bytes from run to run.

drjit's LLVM backend runs a kernel of ``size`` lanes on a pool of ``c`` threads in blocks of
lanes, each taken by whichever thread is free (drjit-core's ``LLVMThreadState::launch``, the same
rule since February 2024 and in drjit 1.5.0, which seahaze pins):

- ``c = 1``: one block;
- at most ``c`` SIMD packets: one packet per block;
- ``size ≤ 2·c·B``: ``2·c`` blocks of equal whole packets;
- beyond: blocks of ``B`` lanes, ``B`` = 16,384 (:data:`BLOCK_LANES`; drjit's Python API does not
  change it, and its C API takes only powers of two).

A render sums each pixel's samples into per-thread copies of the image, added together after the
kernel. A pixel whose samples straddle two blocks taken by two threads gets two partial sums,
added in another order than one thread's running sum: its value changes in the last bits from run
to run. At 42 samples per pixel 16,384 lanes end inside a pixel 23 times in a 128×72 image; at a
power of two, never.

:func:`sample_layout` lays the samples out so that every block holds whole pixels. Each block of
``B`` lanes takes as many whole pixels as fit, shifted from its start by a few lanes (its
:meth:`SampleLayout.shift`); the lanes left over (fewer than a pixel's samples plus the largest
shift: 46 of 16,384 at 42 samples, none at a power of two) are padding, which the integrator is
asked for with its lanes inactive and which is summed nowhere. An image too small for the fourth
rule is padded at its end to more than ``2·c`` blocks, so the blocks are always ``B`` lanes and
every sample's lane is the same whatever the thread count. The shift serves the sampler:

- seahaze's sampler draws by sample, not by lane, so a block's pixels start at the same place
  within a SIMD packet (of 4, 8 or 16 lanes) as in one thread's single block: drjit adds a
  packet's lanes of one pixel together before adding them to the sum, and the same grouping
  gives the same bytes as Mitsuba's own order would;
- Mitsuba's samplers draw by lane, and ``multijitter`` stratifies lanes ``k·spp … k·spp + spp −
  1`` together, so a block's pixels start on such a lane (``lane_groups``): its strata stay whole
  pixels. Its random numbers follow the lanes: those of Mitsuba's order where a block holds the
  whole image or the sample count divides ``B``, others (as good) beyond.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

BLOCK_LANES = 16_384
"""drjit's LLVM block size (``jitc_llvm_block_size``): lanes per work item of a large launch."""

WIDEST_PACKET_LANES = 16
"""The widest SIMD packet of drjit's LLVM backend (AVX-512); the narrower ones (8, 4) divide it."""


@dataclass(frozen=True)
class SampleLayout:
    """Lanes in blocks of ``block_lanes``; block ``b`` holds the samples of pixels
    ``b·pixels_per_block …`` (``spp`` neighbouring lanes each) from lane :meth:`shift` of the
    block on; the rest of a block, and every lane of pixel index ``n_pixels`` or above, is
    padding. ``lanes`` is the kernel's size.

    One block of every pixel is the plain layout (:func:`plain_layout`): a pixel's ``s``-th
    sample at lane ``pixel·spp + s``, Mitsuba's own order."""

    n_pixels: int
    spp: int
    pixels_per_block: int
    block_lanes: int
    lanes: int
    shift_step: int = 0
    """A block's shift grows by this many lanes per block, modulo :attr:`shift_modulus`."""
    shift_modulus: int = WIDEST_PACKET_LANES

    def shift(self, block: int) -> int:
        """Lanes between the start of ``block`` and its first pixel's first sample."""
        return block * self.shift_step % self.shift_modulus

    @property
    def padding(self) -> int:
        """Lanes traced and summed nowhere."""
        return self.lanes - self.n_pixels * self.spp


def plain_layout(n_pixels: int, spp: int) -> SampleLayout:
    """Every pixel's samples in one block, one after another."""
    return SampleLayout(n_pixels, spp, n_pixels, n_pixels * spp, n_pixels * spp)


def sample_layout(
    n_pixels: int, spp: int, threads: int, *, lane_groups: bool = False
) -> SampleLayout:
    """The layout of ``n_pixels`` pixels of ``spp`` samples on ``threads`` threads in which no
    pixel's samples straddle two of drjit's blocks (see the module's rules); ``lane_groups``:
    each pixel on lanes ``k·spp … k·spp + spp − 1`` for a Mitsuba sampler, rather than at its
    plain layout's place within a SIMD packet for seahaze's.

    Every sample's lane is the same whatever ``threads``: only the padding at the end grows,
    to more than ``2·threads`` blocks of :data:`BLOCK_LANES` (drjit's fourth rule, the one
    whose blocks the layout follows) when the image fills fewer and there is more than one
    thread. More samples per pixel than a block holds get the plain layout (no layout avoids
    the straddles). Raises ``ValueError`` for counts below 1."""
    if min(n_pixels, spp, threads) < 1:
        raise ValueError(
            f"pixels, samples per pixel and threads must be at least 1, not "
            f"{n_pixels}, {spp} and {threads}"
        )
    blocked = _blocked_layout(n_pixels, spp, lane_groups)
    if blocked is None:
        return plain_layout(n_pixels, spp)
    if threads == 1:
        return blocked  # one block: no padding needed
    return replace(blocked, lanes=max(blocked.lanes, 2 * threads * BLOCK_LANES + 1))


def _blocked_layout(n_pixels: int, spp: int, lane_groups: bool) -> SampleLayout | None:
    """Blocks of :data:`BLOCK_LANES` lanes, each with the most whole pixels that fit beside
    the largest shift a block takes, the last one ending at its last sample; None when not
    even one pixel fits."""
    pixels = BLOCK_LANES // spp
    while pixels > 0:
        if lane_groups:
            # Block b starts at lane b·B: shifted by (−b·B) mod spp, its pixels start on k·spp.
            step, modulus = -BLOCK_LANES % spp, spp
        else:
            # The plain layout puts block b's first pixel at lane b·pixels·spp.
            step, modulus = pixels * spp % WIDEST_PACKET_LANES, WIDEST_PACKET_LANES
        largest_shift = modulus - math.gcd(step, modulus)
        if pixels * spp + largest_shift <= BLOCK_LANES:
            blocks = -(-n_pixels // pixels)
            last = n_pixels - (blocks - 1) * pixels
            layout = SampleLayout(n_pixels, spp, pixels, BLOCK_LANES, 0, step, modulus)
            lanes = (blocks - 1) * BLOCK_LANES + layout.shift(blocks - 1) + last * spp
            return replace(layout, lanes=lanes)
        pixels -= 1
    return None
