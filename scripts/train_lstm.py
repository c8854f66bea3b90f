#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Trains the small next-pose LSTM that `afam` runs live in C++ (Core/src/predict/lstm.cpp).

Offline only; the weights are committed as data/lstm_pose_v1.bin, so neither CI nor the renderer
needs Python or torch. Re-run with Debian's torch:

    apt-get install -y --no-install-recommends python3-torch
    /usr/bin/python3 scripts/train_lstm.py --afam build/Apps/afam --out data/lstm_pose_v1.bin

Training data, all generated: synthetic exploration paths (smooth orbits with varying speed and
turning, distance drifting in [1, 2] and often resting on 1, rare jumps) plus exploration walks of
`afam trajectory --kind walk` (Core's generator, trajectory_gen.hpp) with seeds 1000-1059; walks with
seeds 2000-2009 are the validation set used for model selection. The walks with seeds 101, 202 and
303 are held out for the unit test (LSTM below linear extrapolation) and never used here. Recorded
paths carry no licence and are not trained on: with --trajectories DIR (or AFAM_TRAJECTORIES) the
user_1.dat and user_2.dat there are only evaluated and printed after training.

Model (mirrored exactly by the C++ forward pass):
  positions P_t = d (sin th cos ph, sin th sin ph, cos th) in the volume's normalised frame;
  per step t the features are [ (P_t - P_{t-1}) / DELTA_SCALE , P_t ]  (6 numbers);
  a one-layer LSTM (hidden 32, torch gate order i, f, g, o) reads the last WINDOW steps;
  a linear head maps the last hidden state to r (3 numbers) and the prediction is
  P_{t+1} = P_t + (P_t - P_{t-1}) + DELTA_SCALE * r   (a learned correction of linear extrapolation).

File layout (little-endian), version 1:
  char[8] "AFLSTM\\0\\0"; u32 version; u32 input; u32 hidden; u32 output; u32 window;
  f32 delta_scale; u32 flags (bit 0: residual on linear extrapolation);
  f32 W_ih[4H][I]; f32 W_hh[4H][H]; f32 b[4H] (b_ih + b_hh); f32 W_out[O][H]; f32 b_out[O];
  u32 test_steps T; f32 test_input[T][I]; f32 test_output[O]   (torch's head output for that input);
  u32 FNV-1a 32-bit checksum of every preceding byte.
"""
import argparse
import math
import os
import struct
import subprocess
import sys
import tempfile

import numpy as np
import torch

MAGIC = b"AFLSTM\0\0"
VERSION = 1
INPUT = 6
HIDDEN = 32
OUTPUT = 3
WINDOW = 10
DELTA_SCALE = 0.05
FLAG_RESIDUAL = 1

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TRAIN_SEEDS = range(1000, 1060)
VALIDATION_SEEDS = range(2000, 2010)


def load_trajectory(path):
    a = np.fromfile(path, dtype="<f4")
    n = a.size // 3
    d, th, ph = a[:n], np.radians(a[n:2 * n]), np.radians(a[2 * n:3 * n])
    return np.stack([d * np.sin(th) * np.cos(ph), d * np.sin(th) * np.sin(ph), d * np.cos(th)],
                    1).astype(np.float64)


def generated_walk(afam, seed, n=400):
    """Core's exploration walk (`afam trajectory --kind walk --seed SEED`) as eye positions."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "walk.dat")
        subprocess.run([afam, "trajectory", path, "--kind", "walk", "--views", str(n), "--seed", str(seed),
                        "--quiet"], check=True)
        return load_trajectory(path)


def synthetic_path(rng, n=400):
    """A smooth exploration path: orbit on a sphere whose speed and heading drift, distance in [1, 2]."""
    th = math.radians(rng.uniform(10, 170))
    ph = rng.uniform(0, 2 * math.pi)
    d = rng.uniform(1.0, 1.8)
    u = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
    # tangent heading
    a = np.cross(u, rng.normal(size=3))
    a /= np.linalg.norm(a)
    speed = math.radians(rng.uniform(0.5, 8.0))
    turn = 0.0
    dv = 0.0
    out = []
    for _ in range(n):
        out.append(d * u)
        # speed and turn rate follow slow mean-reverting random walks
        speed += 0.05 * (math.radians(4.0) - speed) + math.radians(rng.normal(0, 0.35))
        speed = min(max(speed, 0.0), math.radians(16.0))
        if rng.random() < 0.01:  # user stops
            speed = math.radians(rng.uniform(0.0, 0.6))
        turn = 0.9 * turn + math.radians(rng.normal(0, 0.6))
        # rotate heading about u by turn, then advance along the great circle
        b = np.cross(u, a)
        a = math.cos(turn) * a + math.sin(turn) * b
        u_new = math.cos(speed) * u + math.sin(speed) * a
        a = -math.sin(speed) * u + math.cos(speed) * a  # transported heading
        u = u_new / np.linalg.norm(u_new)
        a -= u * (a @ u)
        a /= np.linalg.norm(a)
        if rng.random() < 0.006:  # rare jump (recording glitches of 30-60 degrees, as in user_1)
            ang = math.radians(rng.uniform(25, 60))
            c = np.cross(u, rng.normal(size=3))
            c /= np.linalg.norm(c)
            u = math.cos(ang) * u + math.sin(ang) * c
            u /= np.linalg.norm(u)
            a -= u * (a @ u)
            a /= np.linalg.norm(a)
        dv = 0.85 * dv + rng.normal(0, 0.004)
        d = d + dv
        if d < 1.0:
            d, dv = 1.0, max(dv, 0.0) * 0.0
        if d > 2.0:
            d, dv = 2.0, 0.0
    return np.array(out)


def windows(P):
    """(features[WINDOW][6], target residual[3]) for every t with a full window and a next pose."""
    X, Y, base, nxt = [], [], [], []
    D = np.diff(P, axis=0)  # D[k] = P[k+1] - P[k]
    for t in range(WINDOW, len(P) - 1):  # steps t-WINDOW+1..t, each needs P[s-1]
        steps = range(t - WINDOW + 1, t + 1)
        f = [np.concatenate([D[s - 1] / DELTA_SCALE, P[s]]) for s in steps]
        X.append(f)
        lin = P[t] + D[t - 1]
        Y.append((P[t + 1] - lin) / DELTA_SCALE)
        base.append(lin)
        nxt.append(P[t + 1])
    return (np.array(X, np.float32), np.array(Y, np.float32), np.array(base), np.array(nxt))


class PoseLSTM(torch.nn.Module):
    def __init__(self):
        super().__init__()
        self.lstm = torch.nn.LSTM(INPUT, HIDDEN, num_layers=1, batch_first=True)
        self.head = torch.nn.Linear(HIDDEN, OUTPUT)
        with torch.no_grad():  # start as plain linear extrapolation
            self.head.weight.mul_(0.01)
            self.head.bias.zero_()

    def forward(self, x):
        y, _ = self.lstm(x)
        return self.head(y[:, -1, :])


def mean_error(model, X, base, nxt):
    with torch.no_grad():
        r = model(torch.from_numpy(X)).double().numpy()
    pred = base + DELTA_SCALE * r
    return float(np.linalg.norm(pred - nxt, axis=1).mean()), float(np.linalg.norm(base - nxt, axis=1).mean())


def full_trajectory_errors(model, P):
    """Mean next-position error over a whole trajectory, as `afam predict` computes it (for t >= 1)."""
    errs_lstm, errs_lin = [], []
    for t in range(1, len(P) - 1):
        lo = max(1, t - WINDOW + 1)
        f = [np.concatenate([(P[s] - P[s - 1]) / DELTA_SCALE, P[s]]) for s in range(lo, t + 1)]
        with torch.no_grad():
            r = model(torch.tensor(np.array(f, np.float32))[None]).double().numpy()[0]
        lin = P[t] + (P[t] - P[t - 1])
        errs_lstm.append(np.linalg.norm(lin + DELTA_SCALE * r - P[t + 1]))
        errs_lin.append(np.linalg.norm(lin - P[t + 1]))
    return float(np.mean(errs_lstm)), float(np.mean(errs_lin))


def fnv1a(data):
    h = 0x811C9DC5
    for b in data:
        h ^= b
        h = (h * 0x01000193) & 0xFFFFFFFF
    return h


def export(model, path, test_input):
    sd = {k: v.detach().double().numpy() for k, v in model.state_dict().items()}
    with torch.no_grad():
        test_out = model(torch.from_numpy(test_input)[None]).numpy()[0]
    buf = bytearray()
    buf += MAGIC
    buf += struct.pack("<5I", VERSION, INPUT, HIDDEN, OUTPUT, WINDOW)
    buf += struct.pack("<fI", DELTA_SCALE, FLAG_RESIDUAL)
    for arr in (sd["lstm.weight_ih_l0"], sd["lstm.weight_hh_l0"],
                sd["lstm.bias_ih_l0"] + sd["lstm.bias_hh_l0"], sd["head.weight"], sd["head.bias"]):
        buf += np.ascontiguousarray(arr, dtype="<f4").tobytes()
    buf += struct.pack("<I", test_input.shape[0])
    buf += np.ascontiguousarray(test_input, dtype="<f4").tobytes()
    buf += np.ascontiguousarray(test_out, dtype="<f4").tobytes()
    buf += struct.pack("<I", fnv1a(bytes(buf)))
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path + ".tmp", "wb") as f:
        f.write(buf)
    os.replace(path + ".tmp", path)
    return test_out, len(buf)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(ROOT, "data", "lstm_pose_v1.bin"))
    ap.add_argument("--afam", default=os.path.join(ROOT, "build", "Apps", "afam"), help="the afam command line")
    ap.add_argument("--trajectories", default=os.environ.get("AFAM_TRAJECTORIES"),
                    help="folder of recorded user_1.dat / user_2.dat, evaluated after training only")
    ap.add_argument("--synthetic", type=int, default=150, help="synthetic training paths of 400 poses")
    ap.add_argument("--epochs", type=int, default=40)
    ap.add_argument("--seed", type=int, default=5)
    args = ap.parse_args()

    torch.set_num_threads(1)
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)

    walks = [generated_walk(args.afam, s) for s in TRAIN_SEEDS]
    walks_val = [generated_walk(args.afam, s) for s in VALIDATION_SEEDS]
    syn = [synthetic_path(rng) for _ in range(args.synthetic)]
    syn_val = [synthetic_path(rng) for _ in range(15)]

    def stack(paths, repeat=1):
        parts = [windows(p) for p in paths] * repeat
        return tuple(np.concatenate([q[i] for q in parts]) for i in range(4))

    Xtr, Ytr, _, _ = stack(syn + walks)
    Xv, _, Bv, Nv = stack(walks_val)
    Xs, _, Bs, Ns = stack(syn_val)
    print(f"train windows {len(Xtr)}, walk validation windows {len(Xv)}", flush=True)

    model = PoseLSTM()
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, args.epochs)
    Xt, Yt = torch.from_numpy(Xtr), torch.from_numpy(Ytr)
    best, best_state = float("inf"), None
    for ep in range(args.epochs):
        model.train()
        perm = torch.randperm(len(Xt))
        tot = 0.0
        for i in range(0, len(Xt), 256):
            idx = perm[i:i + 256]
            r = model(Xt[idx])
            # the metric is the mean Euclidean error; a smooth version keeps gradients sane near 0
            loss = torch.sqrt(((r - Yt[idx]) ** 2).sum(1) + 1e-4).mean()
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
            opt.step()
            tot += float(loss) * len(idx)
        sched.step()
        model.eval()
        ev, lv = mean_error(model, Xv, Bv, Nv)
        es, ls = mean_error(model, Xs, Bs, Ns)
        score = ev + es
        if score < best:
            best, best_state = score, {k: v.clone() for k, v in model.state_dict().items()}
        print(f"epoch {ep:2d} loss {tot / len(Xt):.4f}  walk val lstm {ev:.4f} (linear {lv:.4f})  "
              f"synthetic val lstm {es:.4f} (linear {ls:.4f})", flush=True)
    model.load_state_dict(best_state)
    model.eval()

    test_input = np.asarray(rng.normal(0, 1, size=(WINDOW, INPUT)), np.float32)
    test_out, size = export(model, args.out, test_input)
    print(f"wrote {args.out} ({size} bytes); test output {test_out}")
    for seed in (101, 202, 303):
        el, en = full_trajectory_errors(model, generated_walk(args.afam, seed))
        print(f"held-out walk seed {seed}: lstm mean_position_error={el:.5f} linear={en:.5f}")
    for name in ("user_1.dat", "user_2.dat"):
        path = os.path.join(args.trajectories or "", name)
        if args.trajectories and os.path.exists(path):
            el, en = full_trajectory_errors(model, load_trajectory(path))
            print(f"recorded {name} (never trained on): lstm mean_position_error={el:.5f} linear={en:.5f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
