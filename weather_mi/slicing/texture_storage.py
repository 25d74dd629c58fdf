"""The slicer's textures' storage: (z, y, x, C) tensors written from C per-voxel channels, the old storage let go
before the new one is built, so that a rebuild (a new scaling, albedo or detail) holds one copy of each texture,
not two (8 M cells and 6 channels: 190 MB less at the peak).

Dr.Jit stores a texture's channels padded to a power of two (6 channels as 8) and builds the padded copy from
the tensor it is given (both held at once while it is built). ``ChannelTextures`` holds C channels as textures of
power-of-two channel counts (6 as 4 + 2): no padding, nothing repacked, and the same trilinear values channel by
channel (each channel is interpolated on its own, with the same weights)."""
from __future__ import annotations

from dataclasses import dataclass


def power_of_two_parts(channels: int) -> list[int]:
    """The channel counts of the textures that hold ``channels`` channels unpadded: its binary digits, largest
    first (6: [4, 2]; 5: [4, 1]; 4: [4])."""
    return [1 << b for b in reversed(range(int(channels).bit_length())) if channels >> b & 1]


@dataclass
class ChannelTextures:
    """C channels (z, y, x) as a tuple of textures of power-of-two channel counts (``power_of_two_parts``), read
    as one: ``eval(tc)`` gives the C channels' values in order. A dataclass of textures: ``dr.freeze`` traverses
    it."""

    parts: tuple

    @classmethod
    def zeros(cls, make, mi, channels: int) -> "ChannelTextures":
        """Textures of one voxel (zeros) for ``channels`` channels; ``make(tensor)``: a texture of a tensor."""
        return cls(tuple(make(mi.TensorXf(mi.Float([0.0] * c), shape=(1, 1, 1, c)))
                         for c in power_of_two_parts(channels)))

    @property
    def channels(self) -> int:
        return sum(int(t.shape[-1]) for t in self.parts)

    def eval(self, tc) -> list:
        """The channels' trilinear values at texture coordinates ``tc`` (a list of C Floats)."""
        return [v for t in self.parts for v in t.eval(tc)]

    def split(self, channels: list) -> list:
        """(texture, its channels) pairs of a list of C flat arrays."""
        out, c0 = [], 0
        for t in self.parts:
            c = int(t.shape[-1])
            out.append((t, channels[c0:c0 + c]))
            c0 += c
        return out


def interleave(mi, channels):
    """Flat array with the channels interleaved (voxel-major), as a (..., C) tensor's storage: one kernel
    over the voxels that scatters each voxel's C values."""
    import drjit as dr
    C = len(channels)
    if C == 1:
        return channels[0]
    n = dr.width(channels[0])
    vox = dr.arange(mi.UInt32, n) * C
    out = dr.empty(mi.Float, n * C)  # every element is written below
    for c in range(C):
        dr.scatter(out, channels[c], vox + c)
    return out


def replace_storage(mi, textures, shape: tuple) -> None:
    """Set each texture of ``textures`` ((texture, channels) pairs: channels a list of flat per-voxel arrays of
    ``shape`` (z, y, x); a ``ChannelTextures`` takes its parts' shares in order) to the tensor of its channels;
    every old storage is dropped first (a one-voxel stand-in of the same channels: nothing reads the textures in
    between)."""
    pairs = []
    for tex, channels in textures:
        pairs += tex.split(channels) if isinstance(tex, ChannelTextures) else [(tex, channels)]
    for tex, channels in pairs:
        tex.set_tensor(mi.TensorXf(mi.Float([0.0] * len(channels)), shape=(1, 1, 1, len(channels))))
    for tex, channels in pairs:
        tex.set_tensor(mi.TensorXf(interleave(mi, channels), shape=tuple(shape) + (len(channels),)))


__all__ = ["ChannelTextures", "interleave", "power_of_two_parts", "replace_storage"]
