#!/usr/bin/env python3
"""Trains cablecell's cable segmentation network and exports it to ONNX.

The network turns a BGR camera image into the probability, per pixel, that
the pixel belongs to an electrical cable. It is a small (185k parameters)
U-Net that runs at half the camera's resolution (320x240 for a 640x480
image); the Rust side (src/perception/vision/network/) resizes the image
down, runs the model with ONNX Runtime, resizes the probability map back up
and thresholds it.

Data:
- real photographs: the cables-dev folder (images 00000..00044 of the
  `cable_dataset_simple` part of the "Cables Dataset" of De Gregorio, Palli
  and Di Stefano, from "Let's take a Walk on Superpixels Graphs: Deformable
  Linear Objects Segmentation and Model Estimation", arXiv 1810.04461).
  Images 00000..00029 train; 00030..00044 are held out and only measured.
- synthetic images from the project's renderer (src/sim/render/), written
  by `cablecell render-dataset` in the same layout: shaded tubes over plain
  and cluttered backgrounds (noise, stripes, checkers, wood, print), with
  crossings, light, blur and noise. Their masks are exact by construction.

The float model is then quantized to 8-bit integers
(quantize_segmentation.py, which also runs alone), the model the Rust side
runs; the float one is kept beside it, as NAME_float.onnx, for comparison.
The exported models' contract (what Rust must do) is in models/README.md:
input `bgr`, shape [1, H, W, 3] (NHWC), the image's B, G, R values as they
are (no scaling: the model normalises inside), float32 0..255 for the float
model and the bytes (uint8) for the 8-bit one; H and W multiples of 16;
output `cable_probability`, float32, [1, 1, H, W], in [0, 1].

Run (from the project's root):
    cargo run --release -- render-dataset target/render-train --count 2000 --seed 11 \
        --min-cables 2 --max-cables 8 --min-diameter-px 4 --max-diameter-px 12
    python3 -m venv .venv-train
    .venv-train/bin/pip install -r models/requirements.txt
    nice .venv-train/bin/python models/train_segmentation.py \
        --synthetic target/render-train --out models/cable_segmentation.onnx
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import random
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

from quantize_segmentation import conv_weights, quantize

# The camera's size and the size the network runs at.
FULL_W, FULL_H = 640, 480
NET_W, NET_H = 320, 240

# Per-channel normalisation applied inside the model, in B, G, R order, on
# values scaled to [0, 1]. Rust feeds raw 0..255 values.
MEAN_BGR = (0.5, 0.5, 0.5)
STD_BGR = (0.25, 0.25, 0.25)

PHOTO_IDS = list(range(0, 45))
# The photographs held out of training by default: the fold the project's
# figures on photographs are measured on (`--held-out` picks another fold,
# or none).
HELD_OUT_IDS = list(range(30, 45))

# `--time-limit-s` times the steps between these two and fits the run's
# length to the time from them: past the workers' start and the batches
# they made while the device started, at the pace they keep.
FIT_FROM_STEP, FIT_TO_STEP = 100, 300


def id_ranges(text: str) -> list[int]:
    """Photograph numbers from "30-44", "0-14,40" or "none"."""
    if text == "none":
        return []
    ids: list[int] = []
    for part in text.split(","):
        low, _, high = part.partition("-")
        ids.extend(range(int(low), int(high or low) + 1))
    return ids


# --------------------------------------------------------------------------
# Model
# --------------------------------------------------------------------------


class ConvBnAct(nn.Sequential):
    def __init__(self, cin: int, cout: int, k: int = 3, stride: int = 1, act: bool = True):
        layers: list[nn.Module] = [
            nn.Conv2d(cin, cout, k, stride=stride, padding=k // 2, bias=False),
            nn.BatchNorm2d(cout),
        ]
        if act:
            layers.append(nn.ReLU(inplace=True))
        super().__init__(*layers)


class CableNet(nn.Module):
    """A tiny U-Net of plain 3x3 convolutions (on 2 CPU cores they train
    several times faster than depthwise-separable ones and run as fast in
    ONNX Runtime at this size): an encoder of five scales (1 .. 1/16, two
    convolutions each, strided at the start of each scale), and a decoder that
    upsamples bilinearly, adds a 1x1-projected skip and convolves once per
    scale; a 1x1 head gives one logit per pixel. With `from_half` the first
    scale is left out (models/history.md says what that cost). `deep_blocks`
    residual blocks at the coarsest scale add capacity and context at almost
    no cost in time; each starts as the identity, so a network fine-tuned
    from one without them starts where it stood."""

    def __init__(self, widths: tuple[int, ...] = (16, 24, 32, 48, 64), from_half: bool = False,
                 deep_blocks: int = 0):
        super().__init__()
        w0, w1, w2, w3, w4 = widths
        # `from_half`: the first convolution strides straight to half
        # size and the logits are upsampled at the end.
        self.from_half = from_half
        mean = torch.tensor(MEAN_BGR).view(1, 3, 1, 1) * 255.0
        std = torch.tensor(STD_BGR).view(1, 3, 1, 1) * 255.0
        self.register_buffer("mean", mean, persistent=False)
        self.register_buffer("std", std, persistent=False)
        if from_half:
            self.enc1 = nn.Sequential(ConvBnAct(3, w1, stride=2), ConvBnAct(w1, w1))
        else:
            self.enc0 = nn.Sequential(ConvBnAct(3, w0), ConvBnAct(w0, w0))
            self.enc1 = nn.Sequential(ConvBnAct(w0, w1, stride=2), ConvBnAct(w1, w1))
        self.enc2 = nn.Sequential(ConvBnAct(w1, w2, stride=2), ConvBnAct(w2, w2))
        self.enc3 = nn.Sequential(ConvBnAct(w2, w3, stride=2), ConvBnAct(w3, w3))
        self.enc4 = nn.Sequential(ConvBnAct(w3, w4, stride=2), ConvBnAct(w4, w4))
        self.deep = nn.ModuleList(nn.Sequential(ConvBnAct(w4, w4), ConvBnAct(w4, w4, act=False))
                                  for _ in range(deep_blocks))
        for block in self.deep:
            nn.init.zeros_(block[1][0].weight)
        self.lat3 = nn.Conv2d(w3, w4, 1)
        self.dec3 = ConvBnAct(w4, w3)
        self.lat2 = nn.Conv2d(w2, w3, 1)
        self.dec2 = ConvBnAct(w3, w2)
        self.lat1 = nn.Conv2d(w1, w2, 1)
        self.dec1 = ConvBnAct(w2, w1)
        if from_half:
            self.head = nn.Conv2d(w1, 1, 1)
        else:
            self.lat0 = nn.Conv2d(w0, w1, 1)
            self.dec0 = ConvBnAct(w1, w0)
            self.head = nn.Conv2d(w0, 1, 1)

    @staticmethod
    def _up(x: torch.Tensor) -> torch.Tensor:
        return F.interpolate(x, scale_factor=2.0, mode="bilinear", align_corners=False)

    def logits(self, x_nchw_255: torch.Tensor) -> torch.Tensor:
        x = (x_nchw_255 - self.mean) / self.std
        if self.from_half:
            s1 = self.enc1(x)
        else:
            s0 = self.enc0(x)
            s1 = self.enc1(s0)
        s2 = self.enc2(s1)
        s3 = self.enc3(s2)
        s4 = self.enc4(s3)
        for block in self.deep:
            s4 = F.relu(s4 + block(s4))
        d = self.dec3(self._up(s4) + self.lat3(s3))
        d = self.dec2(self._up(d) + self.lat2(s2))
        d = self.dec1(self._up(d) + self.lat1(s1))
        if self.from_half:
            return self._up(self.head(d))
        d = self.dec0(self._up(d) + self.lat0(s0))
        return self.head(d)

    def forward(self, bgr_nhwc: torch.Tensor) -> torch.Tensor:
        """The exported graph: NHWC BGR 0..255 in, probability out."""
        x = bgr_nhwc.permute(0, 3, 1, 2)
        return torch.sigmoid(self.logits(x))


# --------------------------------------------------------------------------
# Real images
# --------------------------------------------------------------------------


def load_real(data: Path, ids: list[int], size: tuple[int, int] | None) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Images (BGR uint8) and union masks (float 0..1), resized to `size`
    (w, h) with area averaging if given, else at full resolution (masks 0/1)."""
    return load_stems(data, [f"{i:05d}" for i in ids], size)


def load_stems(data: Path, stems: list[str], size: tuple[int, int] | None) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """`load_real` for the images `STEM.jpg` with `STEM_mask_all.png` of a
    folder in the cables-dev layout."""
    images, masks = [], []
    for stem in stems:
        img = cv2.imread(str(data / f"{stem}.jpg"), cv2.IMREAD_COLOR)
        m = cv2.imread(str(data / f"{stem}_mask_all.png"), cv2.IMREAD_GRAYSCALE)
        if img is None or m is None:
            raise FileNotFoundError(f"{data}: image or mask {stem} missing")
        m = (m > 127).astype(np.float32)
        if size is not None:
            img = cv2.resize(img, size, interpolation=cv2.INTER_AREA)
            m = cv2.resize(m, size, interpolation=cv2.INTER_AREA)
        images.append(img)
        masks.append(m)
    return images, masks


def load_synthetic(folder: Path, limit: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The first `limit` images of a folder written by `cablecell
    render-dataset`, at the network's size."""
    stems = sorted(p.stem for p in folder.glob("*.jpg"))[:limit]
    if not stems:
        raise FileNotFoundError(
            f"{folder}: no rendered images; make them with "
            f"`cablecell render-dataset {folder} --count 2000 --seed 11`"
        )
    return load_stems(folder, stems, (NET_W, NET_H))


def load_folders(folders: list[Path], limit: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The first `limit` images of each rendered folder, as one set."""
    images, masks = [], []
    for folder in folders:
        more_images, more_masks = load_synthetic(folder, limit)
        images.extend(more_images)
        masks.extend(more_masks)
    return images, masks


def recolour_background(rng: np.random.Generator, img: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The image with everything but the cables given one random, strong
    hue, its shading kept: pale cables on coloured paper, which the real
    training photographs (white paper, wood) lack. Only for rendered
    images, whose masks are exact; their soft edges blend the two."""
    hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV)
    hsv[..., 0] = rng.integers(0, 180)
    hsv[..., 1] = np.clip(hsv[..., 1].astype(np.int32) + rng.integers(60, 160), 0, 255)
    tinted = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR).astype(np.float32)
    cable = np.clip(mask, 0, 1)[..., None]
    return (cable * img + (1 - cable) * tinted).round().astype(np.uint8)


def load_cutouts(data: Path, ids: list[int]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every labelled cable of the given photographs, cut out along its own
    mask (`NNNNN_mask_K.png`) at the network's size: (BGR patch, mask
    patch 0..1). Pasted over rendered backgrounds they give real cables,
    their colours, sheen and ends, on scenes no photograph shows."""
    cutouts = []
    for i in ids:
        img = cv2.imread(str(data / f"{i:05d}.jpg"), cv2.IMREAD_COLOR)
        if img is None:
            raise FileNotFoundError(f"{data}: image {i:05d} missing")
        img = cv2.resize(img, (NET_W, NET_H), interpolation=cv2.INTER_AREA)
        for path in sorted(data.glob(f"{i:05d}_mask_[0-9]*.png")):
            m = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
            m = cv2.resize((m > 127).astype(np.float32), (NET_W, NET_H), interpolation=cv2.INTER_AREA)
            ys, xs = np.nonzero(m > 0.5)
            if len(xs) < 30:
                continue
            x0, x1, y0, y1 = xs.min(), xs.max() + 1, ys.min(), ys.max() + 1
            cutouts.append((img[y0:y1, x0:x1].copy(), m[y0:y1, x0:x1].copy()))
    return cutouts


def made_pale(rng: np.random.Generator, patch: np.ndarray, pm: np.ndarray) -> np.ndarray:
    """A cut-out cable turned white or pale grey, its sheen and shading
    kept: the training photographs hold few such cables (about one in
    twelve), and a light one over light paint is what the network misses
    most (models/history.md, "Pale cables")."""
    gray = patch.astype(np.float32).mean(axis=2, keepdims=True)
    mean = float(gray[pm > 0.5].mean())  # load_cutouts keeps cutouts of 30 px or more
    pale = rng.uniform(165, 240) + (gray - mean) * rng.uniform(0.5, 1.2) + rng.uniform(-10, 10, 3)
    return np.clip(pale, 0, 255).astype(np.uint8)


def paste_cables(rng: np.random.Generator, img: np.ndarray, mask: np.ndarray,
                 cutouts: list[tuple[np.ndarray, np.ndarray]],
                 pale_fraction: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """`img` with one to four real cables pasted over it, each scaled (the
    paper's cables are up to 2.5 times as thick as cables-dev's), rotated,
    shaded and blurred like the scene (`pale_fraction` of them made pale),
    its mask added to the labels."""
    h, w = mask.shape
    img = img.astype(np.float32)
    mask = mask.copy()
    for _ in range(rng.integers(1, 5)):
        patch, pm = cutouts[rng.integers(0, len(cutouts))]
        if pale_fraction > 0 and rng.random() < pale_fraction:
            patch = made_pale(rng, patch, pm)
        s = rng.uniform(1.0, 2.6)
        a = rng.uniform(-180, 180)
        ph, pw = pm.shape
        mtx = cv2.getRotationMatrix2D((pw / 2, ph / 2), a, s)
        mtx[:, 2] += (rng.uniform(0, w) - pw / 2, rng.uniform(0, h) - ph / 2)
        warped = cv2.warpAffine(patch, mtx, (w, h), flags=cv2.INTER_LINEAR).astype(np.float32)
        alpha = cv2.warpAffine(pm, mtx, (w, h), flags=cv2.INTER_LINEAR)
        if rng.random() < 0.5:
            k = rng.choice([3, 5])
            warped = cv2.GaussianBlur(warped, (k, k), 0)
        warped = warped * rng.uniform(0.7, 1.3) + rng.uniform(-20, 20)
        if rng.random() < 0.3:
            warped = warped[..., rng.permutation(3)]
        a3 = np.clip(alpha, 0, 1)[..., None]
        img = a3 * warped + (1 - a3) * img
        mask = np.maximum(mask, alpha)
    return np.clip(img, 0, 255).round().astype(np.uint8), mask


def augment(rng: np.random.Generator, img: np.ndarray, mask: np.ndarray, crop: int,
            scales: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """A random crop x crop window of a randomly flipped, scaled (within
    `scales`, 3 times in 10 not at all), rotated and recoloured image, with
    its mask warped alike."""
    h, w = mask.shape
    if rng.random() < 0.5:
        img, mask = img[:, ::-1], mask[:, ::-1]
    if rng.random() < 0.5:
        img, mask = img[::-1], mask[::-1]
    s = rng.uniform(*scales) if rng.random() < 0.7 else 1.0
    a = rng.uniform(-180, 180) if rng.random() < 0.5 else rng.uniform(-15, 15)
    # The crop's centre keeps it inside the image; where the crop is the
    # larger (`--crop` over a scaled-down image), it keeps the image inside
    # the crop, and reflection fills the rest.
    half = crop / 2 / s
    cx, cy = (rng.uniform(min(half, side - half), max(half, side - half)) for side in (w, h))
    mtx = cv2.getRotationMatrix2D((cx, cy), a, s)
    mtx[:, 2] += (crop / 2 - cx, crop / 2 - cy)
    img = cv2.warpAffine(np.ascontiguousarray(img), mtx, (crop, crop), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    mask = cv2.warpAffine(np.ascontiguousarray(mask), mtx, (crop, crop), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    img = img.astype(np.float32)
    if rng.random() < 0.3:  # a different colour order: cables come in every colour
        img = img[..., rng.permutation(3)]
    if rng.random() < 0.4:  # hue shift
        hsv = cv2.cvtColor(np.clip(img, 0, 255).astype(np.uint8), cv2.COLOR_BGR2HSV).astype(np.int32)
        hsv[..., 0] = (hsv[..., 0] + rng.integers(0, 180)) % 180
        img = cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2BGR).astype(np.float32)
    # brightness, contrast, per-channel gain, noise
    img = (img - 128) * rng.uniform(0.7, 1.3) + 128 + rng.uniform(-30, 30)
    img *= rng.uniform(0.9, 1.1, 3).astype(np.float32)
    if rng.random() < 0.3:
        img += rng.normal(0, rng.uniform(1, 6), img.shape).astype(np.float32)
    return np.clip(img, 0, 255), np.ascontiguousarray(mask)


# --------------------------------------------------------------------------
# Training
# --------------------------------------------------------------------------


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True, warn_only=True)


def soft_erode(img: torch.Tensor) -> torch.Tensor:
    return torch.min(-F.max_pool2d(-img, (3, 1), 1, (1, 0)), -F.max_pool2d(-img, (1, 3), 1, (0, 1)))


def soft_skeleton(img: torch.Tensor, iterations: int) -> torch.Tensor:
    """A differentiable skeleton (Shit et al., "clDice", CVPR 2021): what
    each erosion takes away that an opening does not give back."""
    def opened(x: torch.Tensor) -> torch.Tensor:
        return F.max_pool2d(soft_erode(x), 3, 1, 1)
    skeleton = F.relu(img - opened(img))
    for _ in range(iterations):
        img = soft_erode(img)
        delta = F.relu(img - opened(img))
        skeleton = skeleton + F.relu(delta - skeleton * delta)
    return skeleton


def centre_lines(target: torch.Tensor) -> torch.Tensor:
    """The labelled masks' centre lines: the ridges of their distance
    transforms (OpenCV, a fraction of the soft skeleton's time)."""
    lines = np.zeros(target.shape, np.float32)
    for i, m in enumerate(target[:, 0].cpu().numpy().astype(np.uint8)):
        dist = cv2.distanceTransform(m, cv2.DIST_L2, 3)
        lines[i, 0] = (dist >= cv2.dilate(dist, np.ones((3, 3), np.uint8))) & (m > 0)
    return torch.from_numpy(lines).to(target.device)


def cl_dice(p: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """1 - clDice: low when the found mask covers the labelled centre lines
    and the found centre lines lie in the labelled mask, so a cable broken
    in two or joined to a stroke of paint costs more than its few pixels.
    Four erosions thin a cable up to 8 network pixels wide; what stays of
    a wider stroke of paint lies outside the labels too."""
    skeleton_t = centre_lines(target)
    skeleton_p = soft_skeleton(p, 4)
    precision = ((skeleton_p * target).sum(dim=(1, 2, 3)) + 1) / (skeleton_p.sum(dim=(1, 2, 3)) + 1)
    sensitivity = ((skeleton_t * p).sum(dim=(1, 2, 3)) + 1) / (skeleton_t.sum(dim=(1, 2, 3)) + 1)
    return 1 - 2 * precision * sensitivity / (precision + sensitivity)


def crop_losses(logits: torch.Tensor, target: torch.Tensor, cl_dice_weight: float = 0.0) -> torch.Tensor:
    """Each crop's loss: weighted cross-entropy plus soft DICE (plus clDice
    at `cl_dice_weight`)."""
    bce = F.binary_cross_entropy_with_logits(logits, target, pos_weight=logits.new_tensor(2.0),
                                             reduction="none").mean(dim=(1, 2, 3))
    p = torch.sigmoid(logits)
    inter = (p * target).sum(dim=(1, 2, 3))
    dice = 1 - (2 * inter + 1) / (p.sum(dim=(1, 2, 3)) + target.sum(dim=(1, 2, 3)) + 1)
    loss = bce + dice
    if cl_dice_weight > 0:
        loss = loss + cl_dice_weight * cl_dice(p, target)
    return loss


def loss_fn(logits: torch.Tensor, target: torch.Tensor, cl_dice_weight: float = 0.0) -> torch.Tensor:
    return crop_losses(logits, target, cl_dice_weight).mean()


def as_batch(crops: list[tuple[np.ndarray, np.ndarray]]) -> tuple[torch.Tensor, torch.Tensor]:
    """Crops (image, mask) as the network's input and target tensors."""
    x = torch.from_numpy(np.stack([c[0] for c in crops])).permute(0, 3, 1, 2).contiguous(
        memory_format=torch.channels_last)
    y = (torch.from_numpy(np.stack([c[1] for c in crops]))[:, None] > 0.5).float()
    return x, y


def hardest(model: "CableNet", candidates: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """The candidate crop the network now does worst on (its loss, without
    a gradient): where paint looks like cable, or a cable like paint."""
    device = next(model.parameters()).device
    x, y = (t.to(device) for t in as_batch(candidates))
    with torch.no_grad():
        losses = crop_losses(model.logits(x), y)
    return candidates[int(losses.argmax())]


def make_batch(rng, real, synth, busy, cutouts, args, model):
    """A batch: real photographs (`--real-fraction`), busy rendered scenes
    (`--busy-fraction`, real cables pasted over `--paste-fraction` of
    them; each the hardest of `--hard-of` crops for `model`) and the
    other rendered scenes."""
    crops = []
    for _ in range(args.batch):
        u = rng.random()
        if u < args.real_fraction:
            source = real
        elif busy is not None and u < args.real_fraction + args.busy_fraction:
            source = busy
        else:
            source = synth
        candidates = []
        for _ in range(args.hard_of if source is busy else 1):
            j = rng.integers(0, len(source[0]))
            img, m = source[0][j], source[1][j]
            if source is busy and cutouts and rng.random() < args.paste_fraction:
                img, m = paste_cables(rng, img, m, cutouts, args.pale_fraction)
            if source is synth and args.recolour_fraction > 0 and rng.random() < args.recolour_fraction:
                img = recolour_background(rng, img, m)
            candidates.append(augment(rng, img, m, args.crop, tuple(args.scales)))
        crops.append(candidates[0] if len(candidates) == 1 else hardest(model, candidates))
    return as_batch(crops)


class BatchStream(torch.utils.data.IterableDataset):
    """Endless batches from `make_batch`, made in worker processes
    (`--workers`) so that a GPU is not kept waiting on one CPU core. Each
    worker draws from its own generator, seeded by the run's seed, the step
    the run starts (or resumes) at and the worker's number: a run is the
    same again for the same number of workers."""

    def __init__(self, data, args, first_step: int):
        super().__init__()
        self.data, self.args, self.first_step = data, args, first_step

    def __iter__(self):
        info = torch.utils.data.get_worker_info()
        rng = np.random.default_rng([self.args.seed, self.first_step, info.id if info else 0])
        while True:
            yield make_batch(rng, *self.data, self.args, None)


def load_onnx_weights(model: CableNet, path: Path) -> None:
    """Starts `model` from an exported model's weights, to fine-tune it on
    new data rather than train from nothing. The export folds each batch
    norm into its convolution, so the convolutions take the folded
    weights and biases (given as the batch norms' shifts) and the batch
    norms become identities, to be kept frozen (`freeze_batch_norms`).
    An 8-bit model's weights are dequantized (`conv_weights`)."""
    import onnx

    weights = conv_weights(onnx.load(str(path)))
    convs = [(name, m) for name, m in model.named_modules() if isinstance(m, nn.Conv2d)]
    if len(weights) != len(convs):
        raise ValueError(f"{path}: {len(weights)} convolutions, the network has {len(convs)}")
    batch_norm_after = {seq[0]: seq[1] for seq in model.modules()
                        if isinstance(seq, ConvBnAct)}
    with torch.no_grad():
        for module_path, conv in convs:
            parts = module_path.split(".")
            name = "".join("/" + ".".join(parts[:k]) for k in range(1, len(parts) + 1)) + "/Conv"
            if name not in weights:
                raise ValueError(f"{path}: no convolution {name}")
            w = torch.from_numpy(weights[name][0].copy())
            b = torch.from_numpy(weights[name][1].copy()) if weights[name][1] is not None else None
            if w.shape != conv.weight.shape:
                raise ValueError(f"{path}: convolution {name} is {tuple(w.shape)}, "
                                 f"the network's {tuple(conv.weight.shape)}")
            conv.weight.copy_(w)
            bn = batch_norm_after.get(conv)
            if bn is not None:
                bn.running_mean.zero_()
                bn.running_var.fill_(1.0 - bn.eps)
                bn.weight.fill_(1.0)
                bn.bias.copy_(b)
            elif b is not None:
                conv.bias.copy_(b)


def conv_count(net: Path | CableNet) -> int:
    """The convolutions of an exported model or of a network."""
    if isinstance(net, CableNet):
        return sum(isinstance(m, nn.Conv2d) for m in net.modules())
    import onnx

    return sum(n.op_type == "Conv" for n in onnx.load(str(net)).graph.node)


def freeze_batch_norms(model: CableNet) -> None:
    """Batch norms in evaluation mode: they keep the folded weights'
    statistics while the rest trains."""
    for m in model.modules():
        if isinstance(m, nn.BatchNorm2d):
            m.eval()


def one_cycle(opt: torch.optim.Optimizer, lr: float, steps: int) -> torch.optim.lr_scheduler.OneCycleLR:
    """The learning rate's schedule over a run of `steps` steps."""
    return torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=lr, total_steps=steps, pct_start=0.1)


def train(args) -> CableNet:
    rng = np.random.default_rng(args.seed)
    t0 = time.time()
    train_ids = [i for i in PHOTO_IDS if i not in args.held_out]
    real = load_real(args.data, train_ids, (NET_W, NET_H))
    synth = load_folders(args.synthetic, args.synthetic_count)
    busy = load_folders(args.busy, args.synthetic_count) if args.busy else None
    cutouts = load_cutouts(args.data, train_ids) if busy is not None else []
    print(f"data: {len(real[0])} real, {len(synth[0])} synthetic, {len(busy[0]) if busy else 0} busy, "
          f"{len(cutouts)} real cables to paste in {time.time() - t0:.1f} s", flush=True)

    model = CableNet(from_half=args.from_half, deep_blocks=args.deep_blocks)
    if args.init is not None and conv_count(args.init) != conv_count(model):
        # From a full network without deep blocks, into one without the
        # full-size scale or with deep blocks: the layers both networks
        # have start from its weights; the new ones from nothing (deep
        # blocks as the identity).
        full = CableNet()
        load_onnx_weights(full, args.init)
        own = model.state_dict()
        shared = {k: v for k, v in full.state_dict().items() if k in own and own[k].shape == v.shape}
        model.load_state_dict(shared, strict=False)
        print(f"starting from {args.init}'s weights for {len(shared)} of {len(own)} tensors", flush=True)
    elif args.init is not None:
        load_onnx_weights(model, args.init)
        print(f"starting from {args.init}'s weights", flush=True)
    device = torch.device(args.device)
    model = model.to(device=device, memory_format=torch.channels_last)
    n_params = sum(p.numel() for p in model.parameters())
    print(f"model: {n_params} parameters", flush=True)
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    sched = one_cycle(opt, args.lr, args.steps)
    checkpoint = args.out.with_name(f"{args.out.stem}.checkpoint.pt")
    # Made now, so that a run is not lost at its first checkpoint.
    checkpoint.parent.mkdir(parents=True, exist_ok=True)
    first = 1
    if args.resume and checkpoint.exists():
        state = torch.load(checkpoint, weights_only=False, map_location=device)
        model.load_state_dict(state["model"])
        opt.load_state_dict(state["opt"])
        sched.load_state_dict(state["sched"])
        rng.bit_generator.state = state["rng"]
        torch.set_rng_state(state["torch_rng"])
        first = state["step"] + 1
        print(f"resumed from {checkpoint} at step {first}", flush=True)
    model.train()
    if args.init is not None:
        freeze_batch_norms(model)
    if args.workers > 0:
        batches = iter(torch.utils.data.DataLoader(
            BatchStream((real, synth, busy, cutouts), args, first), batch_size=None,
            num_workers=args.workers, prefetch_factor=4, pin_memory=device.type == "cuda"))
    else:
        batches = (make_batch(rng, real, synth, busy, cutouts, args, model) for _ in itertools.count())
    t_train = time.time()
    running = 0.0
    last = sched.total_steps  # where the schedule ends, a resumed one's too
    fitting = args.time_limit_s is not None and first == 1
    step = first
    while step <= last:
        x, y = (t.to(device, non_blocking=True) for t in next(batches))
        loss = loss_fn(model.logits(x), y, args.cl_dice_weight)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        sched.step()
        running = 0.95 * running + 0.05 * loss.item() if step > 1 else loss.item()
        if fitting and step == FIT_FROM_STEP:
            t_fit = time.time()
        if fitting and step == FIT_TO_STEP:
            per_step_s = (time.time() - t_fit) / (FIT_TO_STEP - FIT_FROM_STEP)
            fitted = FIT_FROM_STEP + int((args.time_limit_s - (t_fit - t_train)) / per_step_s)
            fitted = max(FIT_TO_STEP, min(last, fitted))
            print(f"{per_step_s:.4f} s a step: {fitted} of {last} steps fit in {args.time_limit_s:.0f} s",
                  flush=True)
            if fitted < last:
                last = fitted
                sched = one_cycle(opt, args.lr, last)
                for _ in range(step):
                    sched.step()
        if step % 50 == 0 or step == last:
            el = time.time() - t_train
            print(f"step {step}/{last} loss {running:.4f} {el:.0f} s ({el / (step - first + 1):.2f} s/step)",
                  flush=True)
        if step % args.checkpoint_every == 0 or step == last:
            torch.save({"model": model.state_dict(), "opt": opt.state_dict(), "sched": sched.state_dict(),
                        "rng": rng.bit_generator.state, "torch_rng": torch.get_rng_state(), "step": step},
                       checkpoint)
        step += 1
    model.eval()
    print(f"training took {time.time() - t_train:.0f} s", flush=True)
    return model.to(device="cpu", memory_format=torch.contiguous_format)


# --------------------------------------------------------------------------
# Export and evaluation (the same pipeline as the Rust code)
# --------------------------------------------------------------------------


def export(model: CableNet, out: Path) -> None:
    import onnx

    model.eval()
    dummy = torch.zeros(1, NET_H, NET_W, 3)
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(
        model,
        (dummy,),
        str(out),
        dynamo=False,
        opset_version=17,
        input_names=["bgr"],
        output_names=["cable_probability"],
        dynamic_axes={"bgr": {1: "height", 2: "width"}, "cable_probability": {2: "height", 3: "width"}},
        do_constant_folding=True,
    )
    m = onnx.load(str(out))
    if m.ir_version > 13:
        m.ir_version = 13
    m.doc_string = (
        "cablecell cable segmentation. Input bgr: float32 [1,H,W,3] NHWC, B,G,R 0..255 unscaled, "
        "H and W multiples of 16 (320x240 for a 640x480 image). Output cable_probability: float32 [1,1,H,W]."
    )
    onnx.checker.check_model(m)
    onnx.save(m, str(out))
    print(f"exported {out}: {out.stat().st_size} bytes, IR version {m.ir_version}, opset {m.opset_import[0].version}", flush=True)


def net_size(w: int, h: int) -> tuple[int, int]:
    """The network's input size for an image of w x h: half size, rounded to
    multiples of 16 (the same rule as network/mod.rs)."""
    return max(1, round(w / 32)) * 16, max(1, round(h / 32)) * 16


def input_type(session) -> type:
    """What the model takes: bytes (the 8-bit model) or float32."""
    return np.uint8 if session.get_inputs()[0].type == "tensor(uint8)" else np.float32


def predict(session, img: np.ndarray) -> np.ndarray:
    """Probability at the image's full size, as network/mod.rs computes it."""
    h, w = img.shape[:2]
    nw, nh = net_size(w, h)
    small = cv2.resize(img, (nw, nh), interpolation=cv2.INTER_AREA)[None].astype(input_type(session))
    prob = session.run(None, {"bgr": small})[0][0, 0]
    return cv2.resize(prob, (w, h), interpolation=cv2.INTER_LINEAR)


def evaluate(onnx_path: Path, data: Path, ids: list[int], thresholds: list[float]) -> dict:
    import onnxruntime as ort

    so = ort.SessionOptions()
    so.intra_op_num_threads = 2
    session = ort.InferenceSession(str(onnx_path), so, providers=["CPUExecutionProvider"])
    images, masks = load_real(data, ids, None)
    results = {}
    for t in thresholds:
        ious, dices = [], []
        for img, m in zip(images, masks):
            pred = predict(session, img) > t
            gt = m > 0.5
            inter = float(np.logical_and(pred, gt).sum())
            union = float(np.logical_or(pred, gt).sum())
            ious.append(inter / max(union, 1))
            dices.append(2 * inter / max(float(pred.sum() + gt.sum()), 1))
        results[t] = {"iou": float(np.mean(ious)), "dice": float(np.mean(dices)), "dice_min": float(np.min(dices))}
    # inference time of the network alone at 320x240, median of 50 runs
    x = np.zeros((1, NET_H, NET_W, 3), input_type(session))
    for _ in range(5):
        session.run(None, {"bgr": x})
    times = []
    for _ in range(50):
        s = time.perf_counter()
        session.run(None, {"bgr": x})
        times.append(time.perf_counter() - s)
    results["median_ms"] = 1000 * float(np.median(times))
    return results


def main() -> int:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=here.parent.parent / "shared" / "data" / "cables-dev",
                        help="the cables-dev folder (default: ../shared/data/cables-dev from the project's root)")
    parser.add_argument("--out", type=Path, default=here / "cable_segmentation.onnx",
                        help="the 8-bit model the Rust side runs; the float model it is quantized from "
                             "is written beside it, as NAME_float.onnx")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--steps", type=int, default=1800)
    parser.add_argument("--batch", type=int, default=16)
    parser.add_argument("--crop", type=int, default=160, help="side of the square training crops, in network pixels")
    parser.add_argument("--lr", type=float, default=4e-3)
    parser.add_argument("--scales", type=float, nargs=2, default=[0.75, 1.35], metavar=("LOW", "HIGH"),
                        help="range of the random rescaling of the half-size images (0.75 shows them at the pipeline's 0.375)")
    parser.add_argument("--synthetic", type=Path, nargs="+",
                        help="folders written by `cablecell render-dataset` (required to train), drawn from "
                             "as one set")
    parser.add_argument("--synthetic-count", type=int, default=2000,
                        help="use at most this many rendered images of each folder")
    parser.add_argument("--held-out", type=id_ranges, default=HELD_OUT_IDS,
                        help="photographs of cables-dev kept out of training and measured, e.g. 30-44 "
                             "(the default), 0-14, or none to train on all 45")
    parser.add_argument("--real-fraction", type=float, default=0.5, help="share of real images in a batch")
    parser.add_argument("--busy", type=Path, nargs="+",
                        help="folders written by `cablecell render-dataset --backgrounds busy`, drawn from as one "
                             "set: the paper's kind of scene, with the training photographs' cables pasted over it")
    parser.add_argument("--busy-fraction", type=float, default=0.3, help="share of busy rendered images in a batch")
    parser.add_argument("--paste-fraction", type=float, default=0.5,
                        help="share of busy images that get real cables pasted over them")
    parser.add_argument("--pale-fraction", type=float, default=0.0,
                        help="share of pasted cables made white or pale grey (made_pale; models/history.md, "
                             "\"Pale cables\")")
    parser.add_argument("--checkpoint-every", type=int, default=200,
                        help="steps between checkpoints (OUT_STEM.checkpoint.pt beside the model)")
    parser.add_argument("--init", type=Path,
                        help="fine-tune this ONNX model (e.g. models/cable_segmentation_float.onnx; an 8-bit one is dequantized) "
                             "instead of training from nothing")
    parser.add_argument("--from-half", action="store_true",
                        help="leave out the network's first scale: the first convolution strides to half size "
                             "and the logits are upsampled at the end (faster on CPUs without 8-bit dot products)")
    parser.add_argument("--deep-blocks", type=int, default=0,
                        help="residual blocks at the coarsest scale (CableNet's deep_blocks; "
                             "not used for the shipped model, see models/history.md)")
    parser.add_argument("--resume", action="store_true", help="go on from the checkpoint, if there is one")
    parser.add_argument("--recolour-fraction", type=float, default=0.0,
                        help="share of rendered images whose background is given a strong hue "
                             "(recolour_background; not used for the shipped model, see models/history.md)")
    parser.add_argument("--cl-dice-weight", type=float, default=0.0,
                        help="weight of a clDice term in the loss, which keeps cables whole "
                             "(0: none; not used for the shipped model, see models/history.md)")
    parser.add_argument("--hard-of", type=int, default=1,
                        help="each busy crop is the hardest of this many for the network as it trains "
                             "(models/history.md, \"Hard busy crops\"; the shipped model does not use it)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--device", default="cpu", help="cpu, or cuda (models/README.md, \"Training on a GPU\")")
    parser.add_argument("--workers", type=int, default=0,
                        help="processes that make the batches beside the training (0: the training process "
                             "itself, as for every network shipped so far); a GPU needs many")
    parser.add_argument("--time-limit-s", type=float,
                        help="train for fewer steps than --steps where they would take longer than this, as "
                             "timed over its steps 100-300 (a GPU call's limit; models/README.md, "
                             "\"Training on a GPU\")")
    parser.add_argument("--eval-only", action="store_true", help="measure existing models")
    args = parser.parse_args()

    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)  # augmentation runs between torch's steps, not beside them
    seed_everything(args.seed)
    if not args.data.is_dir():
        print(f"no data at {args.data}", file=sys.stderr)
        return 2
    if args.device.startswith("cuda") and not torch.cuda.is_available():
        print(f"--device {args.device}: PyTorch sees no GPU here", file=sys.stderr)
        return 2
    if args.workers > 0 and args.hard_of > 1:
        print("--hard-of picks crops with the network as it trains: it needs --workers 0", file=sys.stderr)
        return 2
    float_out = args.out.with_name(f"{args.out.stem}_float.onnx")
    if not args.eval_only and (args.synthetic is None or not all(f.is_dir() for f in args.synthetic)):
        print(f"no rendered images at {args.synthetic}: pass --synthetic DIR, made by "
              "`cablecell render-dataset DIR --count 2000 --seed 11`", file=sys.stderr)
        return 2
    t0 = time.time()
    if not args.eval_only:
        model = train(args)
        export(model, float_out)
        print(f"training and export took {time.time() - t0:.0f} s", flush=True)
        quantize(float_out, args.out, args.data)  # the shipped model
    thresholds = [0.3, 0.4, 0.5, 0.6, 0.7]
    summary = {}
    for name, path in (("float", float_out), ("8-bit", args.out)):
        train_res = evaluate(path, args.data, [i for i in PHOTO_IDS if i not in args.held_out], thresholds)
        held_res = evaluate(path, args.data, args.held_out or PHOTO_IDS, thresholds)
        print(f"{name} model {path}:")
        for t in thresholds:
            print(f"  threshold {t}: train IoU {train_res[t]['iou']:.4f} DICE {train_res[t]['dice']:.4f} | "
                  f"held-out IoU {held_res[t]['iou']:.4f} DICE {held_res[t]['dice']:.4f} "
                  f"(min {held_res[t]['dice_min']:.4f})")
        print(f"  onnxruntime median inference at {NET_W}x{NET_H}, 2 threads: {held_res['median_ms']:.2f} ms")
        summary[name] = {str(k): v for k, v in held_res.items()}
    print(json.dumps({"held_out": summary}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
