"""Monocular metric depth from a user-supplied ONNX model, run with onnxruntime.

fuzzrisk downloads nothing: the user exports or obtains a model and passes its path.
A preset describes how a family of exports wants its input and what its output means:

- ``zoedepth`` (ZoeDepth as exported by ailia-models): input RGB / 255 at the size the
  model fixes (ailia: 384x768 for ZoeD_M12_K, 384x512 for _N and _NK), output metres,
  -99 = no depth.
- ``depth_anything_v2_metric``: input (RGB / 255 - mean) / std with ImageNet statistics,
  sides multiples of 14 (short side 518 when the model leaves it dynamic), output
  ``(B, H, W)`` in metres.
- ``depth_anything_v2_relative``: as above, but the output is relative inverse depth.

Input and output names and shapes are read from the model. The input must be one float
tensor ``(N, 3, H, W)`` (NCHW); dimensions the model fixes are used as they are, and
dynamic ones are chosen from the image: the aspect ratio is kept, the short side becomes
``short_side`` and both sides are rounded to the nearest multiple of ``multiple_of``. The output may
be ``(N, h, w)`` or ``(N, 1, h, w)`` for a batch of N, and ``(h, w)`` for one image (Depth
Anything V2 gives ``(B, H, W)``, ZoeDepth ``(B, 1, H, W)``); it is resized back to the image
with bilinear interpolation. :meth:`OnnxDepthEstimator.estimate_batch` runs images of one
size as one batch (in runs of the batch size the model fixes, if it fixes one).
Invalid output pixels become NaN before the resize, so an interpolated pixel that touches
one is NaN as well: the mask grows by about a pixel and no invalid value leaks into a
number.

A relative model (output grows with nearness, unknown scale) gives depth = ``scale`` /
output and is refused without a ``scale``; for a metric model ``scale`` multiplies the
output (default 1).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

#: ImageNet RGB statistics used by Depth Anything's preprocessing
IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)

#: what a preset's output means
OUTPUT_KINDS = ("metric", "relative_inverse")

#: devices :class:`OnnxDepthEstimator` accepts
DEVICES = ("auto", "cpu", "cuda")

_INPUT_TYPES = {"tensor(float)": np.float32, "tensor(float16)": np.float16}


@dataclass(frozen=True)
class DepthPreset:
    """How one family of ONNX depth exports is fed and read.

    Parameters
    ----------
    name : str
        Preset name.
    mean, std : tuple of 3 float
        Per RGB channel, applied to ``image / 255``: ``(x - mean) / std``.
    output : str
        ``"metric"`` (depth in metres) or ``"relative_inverse"`` (affine-invariant inverse
        depth: larger is nearer).
    invalid_value : float or None
        An exact output value that marks "no depth" (ZoeDepth exports use -99).
    short_side : int
        Short side of the model input, in pixels, when the model leaves it dynamic.
    multiple_of : int
        Both input sides must be multiples of this (14 for ViT-14 backbones).
    interpolation : int
        OpenCV interpolation used to resize the image to the model input.
    """

    name: str
    mean: tuple[float, float, float]
    std: tuple[float, float, float]
    output: str
    invalid_value: float | None
    short_side: int
    multiple_of: int
    interpolation: int

    def __post_init__(self):
        if self.output not in OUTPUT_KINDS:
            raise ValueError(f"preset {self.name}: output = {self.output!r}, expected one of {OUTPUT_KINDS}")
        if len(self.mean) != 3 or len(self.std) != 3 or min(self.std) <= 0:
            raise ValueError(f"preset {self.name}: mean and std need 3 values each, std > 0")
        if self.short_side < 1 or self.multiple_of < 1:
            raise ValueError(f"preset {self.name}: short_side and multiple_of must be >= 1")


#: the known export families, by name
PRESETS = {
    preset.name: preset
    for preset in (
        DepthPreset("zoedepth", (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), "metric", -99.0,
                    short_side=384, multiple_of=32, interpolation=cv2.INTER_LINEAR),
        DepthPreset("depth_anything_v2_metric", IMAGENET_MEAN, IMAGENET_STD, "metric", None,
                    short_side=518, multiple_of=14, interpolation=cv2.INTER_CUBIC),
        DepthPreset("depth_anything_v2_relative", IMAGENET_MEAN, IMAGENET_STD, "relative_inverse", None,
                    short_side=518, multiple_of=14, interpolation=cv2.INTER_CUBIC),
    )
}


class OnnxDepthEstimator:
    """Metric depth maps from RGB images with an ONNX model.

    Parameters
    ----------
    model_path : str or Path
        The ``.onnx`` file. Nothing is downloaded; a missing file is a FileNotFoundError
        that says where to put one.
    preset : str or DepthPreset, default "zoedepth"
        A name in :data:`PRESETS` or a custom :class:`DepthPreset`.
    scale : float or None
        Relative models: depth = scale / output (required). Metric models: depth =
        scale * output (default 1).
    output_name : str or None
        Which model output holds the depth; default the first (ailia's ZoeD_M12_NK has
        two outputs and its depth is the second).
    device : {"auto", "cpu", "cuda"}
        "auto" uses onnxruntime's CUDA provider when it is available, else the CPU;
        "cuda" requires it.
    threads : int or None
        onnxruntime intra-op threads (None: onnxruntime's default).

    Attributes
    ----------
    input_name, output_name : str
    input_shape : list
        The model's declared input shape (ints for fixed dimensions, names otherwise).
    providers : list of str
        The execution providers the session uses.
    """

    def __init__(self, model_path: str | Path, preset: str | DepthPreset = "zoedepth", *,
                 scale: float | None = None, output_name: str | None = None,
                 device: str = "auto", threads: int | None = None):
        import onnxruntime as ort  # imported here: only this class needs it

        self.preset = _resolve_preset(preset)
        self.scale = _resolve_scale(self.preset, scale)
        model_path = Path(model_path)
        if not model_path.is_file():
            raise FileNotFoundError(
                f"ONNX depth model {model_path} not found. fuzzrisk downloads nothing: export or "
                f"obtain a metric monocular depth model as ONNX (preset {self.preset.name!r}; e.g. "
                "ZoeDepth ZoeD_M12_K from the ailia-models collection, or a Depth Anything V2 "
                f"metric export) and save it as {model_path.resolve()}, or pass its actual path"
            )
        if threads is not None and threads < 1:
            raise ValueError(f"threads = {threads}, must be None (onnxruntime's default) or >= 1")
        options = ort.SessionOptions()
        if threads is not None:
            options.intra_op_num_threads = threads
        try:
            self._session = ort.InferenceSession(str(model_path), sess_options=options,
                                                 providers=_providers(device, ort.get_available_providers()))
        except Exception as exc:  # onnxruntime raises its own exception types
            raise ValueError(f"ONNX depth model {model_path}: onnxruntime cannot load it ({exc})") from exc
        self.model_path = model_path
        self.providers = self._session.get_providers()

        inputs = self._session.get_inputs()
        if len(inputs) != 1:
            raise ValueError(
                f"ONNX depth model {model_path}: has {len(inputs)} inputs "
                f"({', '.join(i.name for i in inputs)}), expected one image tensor"
            )
        (model_input,) = inputs
        shape = list(model_input.shape)
        if len(shape) != 4 or shape[1] != 3:
            raise ValueError(
                f"ONNX depth model {model_path}: input {model_input.name!r} has shape {shape}, "
                "expected (N, 3, H, W) (NCHW, RGB)"
            )
        if model_input.type not in _INPUT_TYPES:
            raise ValueError(
                f"ONNX depth model {model_path}: input {model_input.name!r} is {model_input.type}, "
                f"expected one of {', '.join(_INPUT_TYPES)}"
            )
        for axis, side in ((2, "height"), (3, "width")):
            if isinstance(shape[axis], int) and shape[axis] % self.preset.multiple_of:
                raise ValueError(
                    f"ONNX depth model {model_path}: input {side} {shape[axis]} is not a multiple of "
                    f"{self.preset.multiple_of} as preset {self.preset.name!r} expects; wrong preset?"
                )
        names = [o.name for o in self._session.get_outputs()]
        if output_name is None:
            output_name = names[0]
        elif output_name not in names:
            raise ValueError(
                f"ONNX depth model {model_path}: no output {output_name!r}; it has {', '.join(names)}"
            )
        self.input_name = model_input.name
        self.input_shape = shape
        self.output_name = output_name
        self._input_dtype = _INPUT_TYPES[model_input.type]

    def input_size(self, height: int, width: int) -> tuple[int, int]:
        """The model input (height, width) used for an image of ``height`` x ``width``."""
        m = self.preset.multiple_of
        factor = self.preset.short_side / min(height, width)
        size = []
        for axis, side in ((2, height), (3, width)):
            fixed = self.input_shape[axis]
            if isinstance(fixed, int) and fixed > 0:
                size.append(fixed)
            else:  # aspect ratio kept, rounded to the nearest multiple of m (at least m)
                size.append(max(m, int(round(side * factor / m)) * m))
        return size[0], size[1]

    def __call__(self, image: np.ndarray) -> np.ndarray:
        """Depth of one image.

        Parameters
        ----------
        image : ndarray of shape (H, W, 3), uint8
            RGB (convert OpenCV's BGR with ``cv2.cvtColor(image, cv2.COLOR_BGR2RGB)``).

        Returns
        -------
        ndarray of shape (H, W), float32
            Metres; NaN where the model gives no valid depth.
        """
        return self.estimate_batch([image])[0]

    @property
    def max_batch(self) -> int | None:
        """The batch size the model fixes (ZoeDepth exports: 1), None when it is dynamic."""
        n = self.input_shape[0]
        return n if isinstance(n, int) and n > 0 else None

    def estimate_batch(self, images: list[np.ndarray]) -> list[np.ndarray]:
        """Depth of several images, run as batches of the same input size.

        Images of one size go through the network together (in runs of :attr:`max_batch`
        when the model fixes its batch size); the result is the same as one call per
        image, in the order given.

        Parameters
        ----------
        images : list of ndarray of shape (H, W, 3), uint8
            RGB images (sizes may differ).

        Returns
        -------
        list of ndarray of shape (H, W), float32
            Metres per image; NaN where the model gives no valid depth.
        """
        for k, image in enumerate(images):
            if (not isinstance(image, np.ndarray) or image.dtype != np.uint8 or image.ndim != 3
                    or image.shape[2] != 3):
                raise ValueError(
                    f"image {k}: {type(image).__name__} of shape {getattr(image, 'shape', None)} and dtype "
                    f"{getattr(image, 'dtype', None)}, expected a uint8 (H, W, 3) RGB image"
                )
        groups: dict[tuple[int, int], list[int]] = {}
        for k, image in enumerate(images):
            groups.setdefault(image.shape[:2], []).append(k)
        out: list[np.ndarray | None] = [None] * len(images)
        step = self.max_batch or max(1, len(images))
        for (height, width), members in groups.items():
            in_h, in_w = self.input_size(height, width)
            for start in range(0, len(members), step):
                batch = members[start:start + step]
                x = np.stack([self._input(images[k], in_h, in_w) for k in batch])
                (raw,) = self._session.run([self.output_name], {self.input_name: x})
                for k, depth in zip(batch, self._split(np.asarray(raw), len(batch))):
                    out[k] = cv2.resize(self._to_metres(depth), (width, height), interpolation=cv2.INTER_LINEAR)
        return out

    def _input(self, image: np.ndarray, in_h: int, in_w: int) -> np.ndarray:
        """(3, in_h, in_w) network input of one RGB image."""
        resized = cv2.resize(image, (in_w, in_h), interpolation=self.preset.interpolation)
        x = resized.astype(np.float32) / np.float32(255.0)
        x = (x - np.asarray(self.preset.mean, np.float32)) / np.asarray(self.preset.std, np.float32)
        return np.ascontiguousarray(x.transpose(2, 0, 1), dtype=self._input_dtype)

    def _split(self, out: np.ndarray, n: int) -> list[np.ndarray]:
        """The (h, w) maps of a batch of ``n``: output (n, h, w) or (n, 1, h, w); for n = 1 also (h, w)."""
        if n == 1 and out.ndim == 2:
            out = out[None]
        if not (3 <= out.ndim <= 4 and out.shape[0] == n and (out.ndim == 3 or out.shape[1] == 1)
                and min(out.shape[-2:]) >= 1):
            raise ValueError(
                f"ONNX depth model {self.model_path}: output {self.output_name!r} has shape "
                f"{out.shape} for a batch of {n}, expected ({n}, h, w) or ({n}, 1, h, w)"
                + (" or (h, w)" if n == 1 else "")
            )
        return [m.reshape(out.shape[-2:]).astype(np.float32) for m in out]

    def _to_metres(self, raw: np.ndarray) -> np.ndarray:
        invalid = ~np.isfinite(raw) | (raw <= 0)
        if self.preset.invalid_value is not None:
            invalid |= raw == np.float32(self.preset.invalid_value)
        depth = np.full(raw.shape, np.nan, dtype=np.float32)
        if self.preset.output == "metric":
            depth[~invalid] = raw[~invalid] * np.float32(self.scale)
        else:
            depth[~invalid] = np.float32(self.scale) / raw[~invalid]
        return depth

    def __repr__(self) -> str:
        return (f"OnnxDepthEstimator({str(self.model_path)!r}, preset={self.preset.name!r}, "
                f"providers={self.providers})")


def _resolve_preset(preset: str | DepthPreset) -> DepthPreset:
    if isinstance(preset, DepthPreset):
        return preset
    try:
        return PRESETS[preset]
    except (KeyError, TypeError):
        raise ValueError(
            f"preset = {preset!r}, expected one of {', '.join(PRESETS)} or a DepthPreset"
        ) from None


def _resolve_scale(preset: DepthPreset, scale: float | None) -> float:
    if scale is None:
        if preset.output == "relative_inverse":
            raise ValueError(
                f"preset {preset.name!r} is a relative (non-metric) model: its output has no unit. "
                "Give scale (depth = scale / output, metres) calibrated on your camera, or use a "
                "metric model"
            )
        return 1.0
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale = {scale}, must be a finite number > 0")
    return float(scale)


def _providers(device: str, available: list[str]) -> list[str]:
    has_cuda = "CUDAExecutionProvider" in available
    if device == "auto":
        return ["CUDAExecutionProvider", "CPUExecutionProvider"] if has_cuda else ["CPUExecutionProvider"]
    if device == "cpu":
        return ["CPUExecutionProvider"]
    if device == "cuda":
        if not has_cuda:
            raise ValueError(
                f"device = 'cuda' but onnxruntime offers only {', '.join(available)}; install "
                "onnxruntime-gpu with a matching CUDA, or use device='auto' or 'cpu'"
            )
        return ["CUDAExecutionProvider", "CPUExecutionProvider"]
    raise ValueError(f"device = {device!r}, expected one of {', '.join(DEVICES)}")
