"""Training the torch likelihood's ensemble: every member at once, as one batched network (needs torch).

The M members of `perception.learned.TorchModel` share the shape of one small network (input ->
``hidden`` ReLU units -> one score per class) and differ in their initialisation and batch order.
Their weights are stacked, (M, inputs, hidden) and (M, hidden, classes), and trained together:
one batched matrix product (``torch.baddbmm``) per layer and step gives every member's scores on a
minibatch of its own. The loss is the sum of the members' cross-entropies, so each member's
gradient is its own and Adam (elementwise) moves each as if it were trained alone; but one product
over M members is large enough for several threads to pay, where a single small network is not.

Only `perception.learned.fit_torch` calls this; torch is imported by the caller and handed in.
"""

from __future__ import annotations

import math
import os
from contextlib import contextmanager

import numpy as np

__all__ = ["train_ensemble", "all_cores"]

#: Taps per minibatch of each member (fewer on a small training set, so that an epoch is MIN_STEPS steps).
BATCH = 64
#: Fewest optimiser steps per epoch: a hundred taps still take several steps per pass.
MIN_STEPS = 8
#: Smallest first layer (members x inputs x hidden weights) trained on several threads.
MIN_SHARED_WORK = 2 ** 20
#: Temperatures (beta) a member's held-out loss is taken at, the best of them (early stopping).
_BETAS = np.geomspace(0.05, 20.0, 41)
#: Adam's learning rate.
LEARNING_RATE = 3e-3


@contextmanager
def all_cores(torch, *, work: float):
    """Train on every core (``os.cpu_count()`` threads, at most ``$OMP_NUM_THREADS`` when it is set) when a
    step is large enough to share, restoring the caller's thread count after.

    ``work`` is the first layer's weights of all members (members x inputs x hidden). Below
    `MIN_SHARED_WORK` a step lasts well under a millisecond, and threads that wait for each other
    make it slower, not faster (measured on two busy cores: 1.5-3x slower), so one thread trains it.
    ``OMP_NUM_THREADS`` (the variable torch's own default honours) caps it where the cores are shared by
    processes of one job, e.g. the test suite's pytest-xdist workers. The weights do not depend on it.
    """
    threads = torch.get_num_threads()
    torch.set_num_threads(_shared_threads() if work >= MIN_SHARED_WORK else 1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def _shared_threads() -> int:
    """Threads a large step trains on: ``os.cpu_count()``, at most ``$OMP_NUM_THREADS`` (if a number)."""
    cores = max(os.cpu_count() or 1, 1)
    try:
        return max(1, min(cores, int(os.environ.get("OMP_NUM_THREADS", cores))))
    except ValueError:
        return cores


def _initial_weights(torch, members, inputs, hidden, classes, generator):
    """PyTorch's default for a Linear layer, per member: uniform in +-1/sqrt(fan in)."""
    def uniform(shape, fan_in):
        return ((torch.rand(shape, generator=generator) * 2.0 - 1.0) / math.sqrt(fan_in)).requires_grad_()

    return [uniform((members, inputs, hidden), inputs), uniform((members, 1, hidden), inputs),
            uniform((members, hidden, classes), hidden), uniform((members, 1, classes), hidden)]


def _forward(torch, weights, x):
    """Scores (M, B, classes) of inputs x, (M, B, inputs) or (1, B, inputs) shared by the members."""
    w1, b1, w2, b2 = weights
    if x.shape[0] != w1.shape[0]:
        x = x.expand(w1.shape[0], -1, -1)
    return torch.baddbmm(b2, torch.relu(torch.baddbmm(b1, x, w1)), w2)


def _tempered_losses(torch, scores, truth):
    """(M,) held-out cross-entropy of each member's scores (M, N, classes) at its best temperature.

    The model is temperature-scaled after training, so a member is judged by what it becomes then:
    the plain held-out loss rises as soon as a network grows overconfident, which a temperature
    undoes. (A choice of principle: on the few sets compared, the epochs it chose gave the same
    held-out accuracy as the plain loss's.)
    """
    betas = torch.as_tensor(_BETAS, dtype=scores.dtype)[:, None, None, None]
    tempered = torch.log_softmax(betas * scores[None], dim=3)            # (K, M, N, classes)
    index = truth.expand(*tempered.shape[:3])[..., None]
    return (-tempered.gather(3, index)[..., 0].mean(dim=2)).min(dim=0).values.numpy()


def train_ensemble(torch, x, tap_class, n_classes: int, *, members: int, hidden: int, weight_decay: float,
                   seed: int, epochs, held=None, patience: int | None = None, residuals=None,
                   residual_class=None):
    """Train M members together; keep each at its best held-out epoch, or at its own epoch count.

    Parameters
    ----------
    torch : module
    x : (N, inputs) float array
        Standardised, imputed taps.
    tap_class : (N,) int array
        Joint class of each tap.
    n_classes : int
    members, hidden : int
        Ensemble members M and hidden ReLU units per member.
    weight_decay : float
        L2 penalty of Adam.
    seed : int
        Seed of the initialisations and batch orders.
    epochs : int or (M,) int array
        Most epochs (with ``held``), or how many epochs each member trains (without).
    held : (x_held, class_held), optional
        Held-out taps: each member is kept at the epoch of its lowest held-out cross-entropy at its best
        temperature (`_tempered_losses`).
    patience : int, optional
        With ``held``: stop once no member has lowered its held-out loss for this many epochs.
    residuals : (K, inputs) float array, optional
        Within-class deviations: each tap of a minibatch is moved by one of them, drawn afresh at every
        step (`perception.learned.within_class_residuals`), so that the members learn the spread of a
        class rather than its few taps.
    residual_class : (K,) int array, optional
        The class of each deviation: a tap is then moved by a deviation of its own class only (none when
        its class has none), rather than by one drawn from every class.

    Returns
    -------
    weights : list of four float32 ndarrays
        (M, inputs, hidden), (M, hidden), (M, hidden, classes), (M, classes).
    best_epochs : (M,) int ndarray
        Epochs each member trained (with ``held``: to its lowest held-out loss).
    held_scores : (M, N_held, classes) float64 ndarray or None
        Each member's log-softmax scores of the held-out taps at its kept epoch.
    """
    generator = torch.Generator().manual_seed(int(seed))
    torch.manual_seed(int(seed))
    weights = _initial_weights(torch, members, x.shape[1], hidden, n_classes, generator)
    # foreach: Adam's update of the four weight tensors in one multi-tensor pass each, not tensor by tensor
    # (torch's CPU default). The same arithmetic (the weights came out bit-identical on the small station's
    # taps), in half the CPU: there a step's elementwise update of the first layer cost more than its
    # products (a fold's early stopping 3.5-4.9 CPU-s against 1.6-2.5 on one thread).
    optimiser = torch.optim.Adam(weights, lr=LEARNING_RATE, weight_decay=weight_decay, foreach=True)
    inputs = torch.as_tensor(np.asarray(x), dtype=torch.float32)
    targets = torch.as_tensor(np.asarray(tap_class), dtype=torch.long)
    stop = np.broadcast_to(np.asarray(epochs, dtype=np.int64), (members,)).copy()
    kept = [w.detach().clone() for w in weights]
    best_epochs, best_loss = stop.copy(), np.full(members, np.inf)
    held_scores = None
    if held is not None:
        held_x = torch.as_tensor(np.asarray(held[0]), dtype=torch.float32)[None]
        held_class = torch.as_tensor(np.asarray(held[1]), dtype=torch.long)
        held_scores = np.zeros((members, len(held[1]), n_classes))
    batch_size = max(min(BATCH, len(inputs) // MIN_STEPS), 1)
    noise = None
    if residuals is not None and len(residuals):
        noise = torch.as_tensor(np.asarray(residuals), dtype=torch.float32)
        if residual_class is not None:   # deviations sorted by class: class c owns rows first[c]:first[c] + count[c]
            by_class = np.argsort(residual_class, kind="stable")
            noise = torch.cat([noise[torch.as_tensor(by_class)], torch.zeros((1, noise.shape[1]))])   # last row: none
            count = np.bincount(residual_class, minlength=n_classes)
            first = torch.as_tensor(np.concatenate([[0], np.cumsum(count)[:-1]]))
            count = torch.as_tensor(count)
    for epoch in range(1, int(stop.max()) + 1):
        order = torch.stack([torch.randperm(len(inputs), generator=generator) for _ in range(members)])
        for batch in order.split(batch_size, dim=1):           # (M, b): a minibatch of its own per member
            optimiser.zero_grad()
            batch_inputs = inputs[batch]
            if noise is not None and residual_class is None:   # each tap moved by a within-class deviation of another
                batch_inputs = batch_inputs + noise[torch.randint(len(noise), batch.shape, generator=generator)]
            elif noise is not None:   # ... of another tap of its own class
                own = targets[batch]
                pick = first[own] + (torch.rand(batch.shape, generator=generator) * count[own]).long()
                batch_inputs = batch_inputs + noise[torch.where(count[own] > 0, pick, len(noise) - 1)]
            logits = _forward(torch, weights, batch_inputs)
            # Sum over members of each member's mean cross-entropy: the members' gradients stay apart.
            loss = torch.nn.functional.cross_entropy(logits.reshape(-1, n_classes), targets[batch].reshape(-1),
                                                     reduction="sum") / batch.shape[1]
            loss.backward()
            optimiser.step()
        with torch.no_grad():
            if held is None:
                done = torch.as_tensor(np.flatnonzero(stop == epoch))
                for w, k in zip(weights, kept):
                    k[done] = w[done]
                continue
            scores = torch.log_softmax(_forward(torch, weights, held_x), dim=2)
            losses = _tempered_losses(torch, scores, held_class)
            better = np.flatnonzero(losses < best_loss)
            best_loss[better], best_epochs[better] = losses[better], epoch
            held_scores[better] = scores.numpy()[better]
            for w, k in zip(weights, kept):
                k[torch.as_tensor(better)] = w[torch.as_tensor(better)]
            if patience is not None and (epoch - best_epochs).min() >= patience:
                break
    w1, b1, w2, b2 = (k.numpy() for k in kept)
    return [w1, b1[:, 0], w2, b2[:, 0]], best_epochs, held_scores
