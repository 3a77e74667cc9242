"""Block evaluation inside a sweep task: one platform variant's values ``G`` and step flags,
block after block of states, into buffers reused from block to block.

The compiled code (generated function ``envelope``, derive/envelope.py) writes per step only
the values the envelopes maximise, with the step flags, in one call per block. A platform with
sensor effects (which change F after the compiled code) goes through
``Evaluator.evaluate_quiet`` and ``gsfric.sweep.envelope.values`` instead.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from gsfric.compiled import native
from gsfric.compiled.state import state_layout
from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.flags import flag_spec
from gsfric.evaluation.parameters import model_function
from gsfric.platform.catalog import sensor_parameters
from gsfric.platform.description import Platform
from gsfric.sweep.envelope import VALUE_INPUTS, envelope_rows, values
from gsfric.sweep.workspace import SCRATCH
from gsfric.trajectory import Motion


class Block:
    """Buffers of one block of at most ``size`` steps, reused: each step's values ``G`` (the
    generated ``envelope``'s 78 values), the step flags and the workspace states. Belongs to one
    task (never shared between threads). Nothing of the block's size is allocated block after
    block: Dask's workers return freed memory to the system at once
    (``MALLOC_TRIM_THRESHOLD_``), so every such allocation would cost fresh pages.

    Attributes
    ----------
    size : int
        Steps the buffers hold.
    n : int
        Steps of the current block (``use``).
    values : ndarray (n, rows, 6)
        The current block's values ``G``.
    flag : ndarray (n,) int64
        The current block's step flags.
    states : ndarray (size * 36,)
        Workspace states of a block (``Workspace.states_of``'s ``out``).
    times : ndarray (size,)
        Zeros: the times of workspace states.
    pairs : ndarray (size * 18,)
        Scratch of the energies' trapezoid (sums of neighbouring steps).
    """

    def __init__(self, size: int) -> None:
        rows = len(envelope_rows())
        self.size = size
        self._values = np.empty(size * rows * 6)
        self.pairs = np.empty(size * 3 * 6)
        self.states = np.empty(size * (state_layout().size + SCRATCH))
        self.times = np.zeros(size)
        self._flag = np.empty(size, dtype=np.int64)
        self._buffers: dict[str, np.ndarray] = {}
        self.n = 0

    def use(self, n: int) -> None:
        """Lay the buffers out for ``n <= size`` steps (every view C-contiguous)."""
        if n == self.n:
            return
        rows = len(envelope_rows())
        self.n = n
        self.values = self._values[:n * rows * 6].reshape(n, rows, 6)
        self.out = {"G": self.values.reshape(n, rows * 6)}
        self.flag = self._flag[:n]

    def spans(self, n: int) -> Iterator[tuple[int, int]]:
        """The blocks ``s:e`` of ``n`` steps, the buffers laid out for each (``use``)."""
        for s in range(0, n, self.size):
            e = min(n, s + self.size)
            self.use(e - s)
            yield s, e

    def buffer(self, name: str, width: int) -> np.ndarray:
        """A buffer (n, width) of the current block for the output ``name``, reused from
        block to block: the outputs the step flags read, which the compiled code would
        otherwise allocate for every call."""
        buf = self._buffers.get(name)
        if buf is None or buf.size < self.size * width:
            buf = self._buffers[name] = np.empty(self.size * width)
        return buf[:self.n * width].reshape(self.n, width)


class Evaluation:
    """One variant's evaluation of blocks of states into a ``Block``: each step's values
    ``G`` and the step flags, in one call of the compiled code (generated ``envelope``) per
    block.

    ``G`` is what the norms and products of ``Evaluator.evaluate_quiet``'s outputs give (to
    rounding: within 1e-12), with its step flags and coupled-friction flag; a platform with
    sensor effects (which change F after the compiled code) goes through
    ``Evaluator.evaluate_quiet`` itself and ``values``.
    """

    def __init__(self, platform: Platform) -> None:
        self.evaluator = Evaluator(platform, n_threads=1)
        gains, delay = sensor_parameters(platform.effects)
        self.sensor = delay != 0.0 or bool(np.any(gains != 0.0))
        self.spec = None
        if not self.sensor:
            # the platform's own model (derived with its friction model fixed, as evaluate's)
            self.fn = native.get(model_function("envelope", platform.friction.model))
            self.spec = flag_spec(self.fn.outputs, platform.geometry.stroke)
            read = self.spec.outputs_read()
            self.read = [(name, size) for k, (name, size, _) in enumerate(self.fn.outputs)
                         if k in read and name != "G"]
            self.select = ("G", *(name for name, _ in self.read))

    def blocks(self, block: Block, x: np.ndarray, t: np.ndarray) -> Iterator[tuple[int, int]]:
        """Fill ``block`` with the steps ``s:e`` of states x (n, 24) at times t (n,) block
        after block; yields ``(s, e)``."""
        if self.spec is not None:
            return self._compiled(block, x)
        return self._evaluated(block, x, t)

    def _compiled(self, block: Block, x: np.ndarray) -> Iterator[tuple[int, int]]:
        ev = self.evaluator         # every flag, the coupled solve's included, set in C
        for s, e in block.spans(len(x)):
            out = {"G": block.out["G"], **{name: block.buffer(name, width)
                                           for name, width in self.read}}
            self.fn([x[s:e], ev.P, ev.Q], out, 1, select=self.select, flags=self.spec,
                    flag=block.flag)
            yield s, e

    def _evaluated(self, block: Block, x: np.ndarray, t: np.ndarray
                   ) -> Iterator[tuple[int, int]]:
        motion = Motion(t, *state_layout().split(x))
        result = self.evaluator.evaluate_quiet(motion)       # flagged steps are counted
        for s, e in block.spans(len(x)):
            values({k: result.arrays[k][s:e] for k in VALUE_INPUTS}, block.values)
            block.flag[...] = result.flag[s:e]
            yield s, e
