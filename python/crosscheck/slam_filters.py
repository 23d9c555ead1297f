"""The SLAM estimators of spec §3.5 in numpy, vectorised over particles, for the cross-check.

Known association throughout (spec §3.5): a landmark's first sighting is "new" for every particle,
so the new-landmark density p0 is a factor common to all particles and is left out. Each
particle update returns the sampled poses and the log-weight increments and changes the
particles' maps in place. The shared model is in slam_common.py; nothing comes from the C++
library.
"""
import numpy as np

from slam_common import (LOG_DET_2PI_SIGMA2, SIGMA2, jacobians, load_landmarks, log_normal2,
                         metrics, place, predict, predict_jacobian, residual, systematic_resample)

LOG_2PI = float(np.log(2 * np.pi))
EYE2 = np.eye(2)


class Particles:
    """Poses x (M, 3) and per-particle landmark means mu (M, K, 2) and covariances (M, K, 2, 2)."""

    def __init__(self, pose0, m, k):
        self.x = np.tile(pose0, (m, 1))
        self.mu = np.zeros((m, k, 2))
        self.cov = np.zeros((m, k, 2, 2))

    def take(self, idx):
        self.x, self.mu, self.cov = self.x[idx], self.mu[idx], self.cov[idx]


def draw(mean, chol, rng):
    """mean + chol xi per row; chol is lower triangular (M, 3, 3)."""
    return mean + np.einsum("mij,mj->mi", chol, rng.standard_normal(mean.shape))


def ekf_landmark_update(p, k, z):
    """EKF update of landmark k of every particle at its (already sampled) pose."""
    e, dx, dy, r = residual(p.x, p.mu[:, k], z)
    _, hm = jacobians(dx, dy, r)
    pk = p.cov[:, k]
    s = hm @ pk @ hm.transpose(0, 2, 1) + SIGMA2
    gain = pk @ hm.transpose(0, 2, 1) @ np.linalg.inv(s)
    p.mu[:, k] = p.mu[:, k] - np.einsum("mij,mj->mi", gain, e)  # innovation wrap(z - h) = -e
    a = EYE2[None] - gain @ hm
    c = a @ pk @ a.transpose(0, 2, 1) + gain @ SIGMA2 @ gain.transpose(0, 2, 1)
    p.cov[:, k] = 0.5 * (c + c.transpose(0, 2, 1))


def new_landmark_ekf(p, f, sigma1, k, z, rng):
    """FastSLAM and (B): x from the motion prior, the landmark at g(x, z) with G_z Sigma2 G_z^T."""
    p.x = draw(f, np.linalg.cholesky(sigma1), rng)
    m, _, gz = place(p.x, z)
    p.mu[:, k], p.cov[:, k] = m, gz @ SIGMA2 @ gz.transpose(0, 2, 1)
    return np.zeros(len(f))


def fastslam2_update(p, f, sigma1, k, z, new, rng):
    """FastSLAM 2.0 (spec §3.5): the proposal linearised at f, weight N(nu; 0, H_x S1 H_x^T + Q)."""
    if new:
        return new_landmark_ekf(p, f, sigma1, k, z, rng)
    e, dx, dy, r = residual(f, p.mu[:, k], z)
    hx, hm = jacobians(dx, dy, r)
    qj = SIGMA2 + hm @ p.cov[:, k] @ hm.transpose(0, 2, 1)
    # Sigma_x = (H_x^T Qj^-1 H_x + Sigma1^-1)^-1 without inverting the ill-conditioned Sigma1:
    # with Sigma1 = L1 L1^T, Sigma_x = L1 (I + B^T Qj^-1 B)^-1 L1^T, B = H_x L1.
    l1 = np.linalg.cholesky(sigma1)
    bm = hx @ l1
    qinv = np.linalg.inv(qj)
    inner = np.eye(3)[None] + bm.transpose(0, 2, 1) @ qinv @ bm
    nu = -e
    # mu_x = f + Sigma_x H_x^T Qj^-1 nu = f + L1 inner^-1 B^T Qj^-1 nu.
    rhs = np.einsum("mji,mjk,mk->mi", bm, qinv, nu)
    mean = f + np.einsum("mij,mj->mi", l1, np.linalg.solve(inner, rhs[..., None])[..., 0])
    c = np.linalg.cholesky(inner)  # inner = C C^T, Sigma_x = L1 C^-T C^-1 L1^T
    xi = rng.standard_normal(f.shape)
    u = np.linalg.solve(c.transpose(0, 2, 1), xi[..., None])[..., 0]
    p.x = mean + np.einsum("mij,mj->mi", l1, u)
    log_inc = log_normal2(nu, hx @ sigma1 @ hx.transpose(0, 2, 1) + qj)
    ekf_landmark_update(p, k, z)
    return log_inc


# ---- Implicit sampling (spec §3.3, §3.5) -------------------------------------------------------

def objective(x, f, s1inv, m, z, sinv, order=2):
    """F(x) without constants, its gradient and exact and Gauss-Newton Hessians, per row."""
    d = x - f
    e, dx, dy, r = residual(x, m, z)
    val = 0.5 * np.einsum("mi,mij,mj->m", d, s1inv, d) + 0.5 * np.einsum("mi,mij,mj->m", e, sinv, e)
    if order == 0:
        return val
    hx, _ = jacobians(dx, dy, r)
    a = np.einsum("mij,mj->mi", sinv, e)  # S^-1 e: weights of the second-derivative terms
    grad = np.einsum("mij,mj->mi", s1inv, d) + np.einsum("mji,mj->mi", hx, a)
    gn = s1inv + hx.transpose(0, 2, 1) @ sinv @ hx
    r3, r4 = r**3, r**4
    second = np.zeros_like(gn)  # sum_i (S^-1 e)_i times the Hessian of e_i, (x, y) block only
    second[:, 0, 0] = a[:, 0] * dy**2 / r3 + a[:, 1] * 2 * dx * dy / r4
    second[:, 1, 1] = a[:, 0] * dx**2 / r3 - a[:, 1] * 2 * dx * dy / r4
    second[:, 0, 1] = second[:, 1, 0] = -a[:, 0] * dx * dy / r3 + a[:, 1] * (dy**2 - dx**2) / r4
    return val, grad, gn + second, gn


def positive_definite(h):
    """Sylvester's criterion for each symmetric 3x3 row (cheaper than eigenvalues)."""
    m2 = h[:, 0, 0] * h[:, 1, 1] - h[:, 0, 1] ** 2
    return (h[:, 0, 0] > 0) & (m2 > 0) & (np.linalg.det(h) > 0)


def spd_choice(exact, gn):
    """The exact Hessian where it is positive definite, the Gauss-Newton one elsewhere."""
    pd = positive_definite(exact)
    return np.where(pd[:, None, None], exact, gn)


def minimise(f, s1inv, m, z, sinv, iterations=50, decrement_tol=1e-14):
    """Newton with Armijo backtracking from f, all particles at once (spec §3.3).

    A particle stops when its Newton decrement g^T H^-1 g falls below decrement_tol: F is a
    negative log density, so smaller changes of F are round-off. The sufficient-decrease test
    allows the round-off of F itself, which otherwise rejects every step near the minimum.
    """
    x = f.copy()
    active = np.ones(len(f), bool)
    for _ in range(iterations):
        val, grad, exact, gn = objective(x, f, s1inv, m, z, sinv)
        h = spd_choice(exact, gn)
        step = -np.linalg.solve(h, grad[..., None])[..., 0]
        slope = (grad * step).sum(1)
        active &= -slope > decrement_tol
        if not active.any():
            break
        idx = np.flatnonzero(active)
        t = np.ones(len(idx))
        todo = np.ones(len(idx), bool)
        allowance = 1e-13 * (1 + np.abs(val[idx]))
        for _ in range(40):
            rows = idx[todo]
            trial = x[rows] + t[todo, None] * step[rows]
            ft = objective(trial, f[rows], s1inv[rows], m[rows], z, sinv[rows], order=0)
            ok = ft <= val[rows] + 1e-4 * t[todo] * slope[rows] + allowance[todo]
            x[rows[ok]] = trial[ok]
            done = np.flatnonzero(todo)[ok]
            todo[done] = False
            if not todo.any():
                break
            t[todo] *= 0.5
        active[idx[todo]] = False  # no decrease found: x is a minimum to round-off
    _, _, exact, gn = objective(x, f, s1inv, m, z, sinv)
    return x, spd_choice(exact, gn)


def safe_cholesky(h):
    """Cholesky factors of the rows of h that are finite and positive definite (identity for the
    others) and the mask of those rows."""
    ok = np.isfinite(h).all((1, 2))
    ok[ok] = positive_definite(h[ok])
    h = np.where(ok[:, None, None], h, np.eye(h.shape[1])[None])
    try:
        return np.linalg.cholesky(h), ok
    except np.linalg.LinAlgError:  # an eigenvalue positive only to round-off: row by row
        out = np.tile(np.eye(h.shape[1]), (len(h), 1, 1))
        for j in range(len(h)):
            try:
                out[j] = np.linalg.cholesky(h[j])
            except np.linalg.LinAlgError:
                ok[j] = False
        return out, ok


def implicit_known(p, f, sigma1, k, z, rng, point_landmarks):
    """Implicit step with a known landmark: (A) S = Sigma2 at the point landmark, (B) S frozen at
    (f, m_k) with the EKF landmark covariance; linear map around the minimiser of F."""
    m = p.mu[:, k]
    s = np.broadcast_to(SIGMA2, (len(f), 2, 2)).copy()
    if not point_landmarks:
        _, dx, dy, r = residual(f, m, z)
        _, hm = jacobians(dx, dy, r)
        s = s + hm @ p.cov[:, k] @ hm.transpose(0, 2, 1)
    sinv = np.linalg.inv(s)
    s1inv = np.linalg.inv(sigma1)
    mu, hess = minimise(f, s1inv, m, z, sinv)
    lh, ok = safe_cholesky(hess)
    xi = rng.standard_normal(f.shape)
    p.x = mu + np.linalg.solve(lh.transpose(0, 2, 1), xi[..., None])[..., 0]
    p.x[~ok] = f[~ok]
    const = 0.5 * np.log(np.linalg.det(2 * np.pi * sigma1)) + 0.5 * np.log(
        np.linalg.det(2 * np.pi * s))
    log_det_l = np.log(np.diagonal(lh, axis1=1, axis2=2)).sum(1)
    fx = objective(p.x, f, s1inv, m, z, sinv, order=0)
    log_inc = 1.5 * LOG_2PI - log_det_l + 0.5 * (xi**2).sum(1) - fx - const
    log_inc[~ok | ~np.isfinite(log_inc)] = -np.inf  # a failed particle drops out, NaN never spreads
    if not point_landmarks:
        ekf_landmark_update(p, k, z)
    return log_inc


def implicit_a_new(p, f, sigma1, k, z, rng):
    """(A), new landmark: the 5-D linear map of spec §3.5, drawn in its factored form.

    N(mu, H^-1) with mu = (f, g(f, z)) and H = blockdiag(Sigma1^-1, 0) + J^T Sigma2^-1 J has pose
    marginal N(f, Sigma1) and, given the pose X, landmark theta ~ N(g - J_th^-1 J_x (X - f),
    J_th^-1 Sigma2 J_th^-T) (J = [J_x, J_th] = de/d(x, theta) at mu). The weight p/q is then
    N(e(X, theta); 0, Sigma2) / (N(J_th (theta - mean); 0, Sigma2) |det J_th|) with |det J_th| =
    1/z_r: the 5-D weight, without forming the ill-conditioned Sigma1^-1.
    """
    g, _, _ = place(f, z)
    _, dx, dy, r = residual(f, g, z)
    jx, jth = jacobians(dx, dy, r)
    p.x = draw(f, np.linalg.cholesky(sigma1), rng)
    xi2 = rng.standard_normal((len(f), 2))
    u = np.einsum("ij,mj->mi", np.linalg.cholesky(SIGMA2), xi2)  # J_th (theta - mean)
    shift = np.einsum("mij,mj->mi", jx, p.x - f)
    theta = g + np.linalg.solve(jth, (u - shift)[..., None])[..., 0]
    p.mu[:, k] = theta
    e, _, _, _ = residual(p.x, theta, z)
    log_target = log_normal2(e, np.broadcast_to(SIGMA2, (len(f), 2, 2)))
    log_proposal = -0.5 * (xi2**2).sum(1) - 0.5 * LOG_DET_2PI_SIGMA2 - np.log(z[0])
    return log_target - log_proposal


def update(method, p, f, sigma1, k, z, new, rng):
    if method == "fastslam2":
        return fastslam2_update(p, f, sigma1, k, z, new, rng)
    if method == "implicit":
        if new:
            return implicit_a_new(p, f, sigma1, k, z, rng)
        return implicit_known(p, f, sigma1, k, z, rng, point_landmarks=True)
    if new:
        return new_landmark_ekf(p, f, sigma1, k, z, rng)
    return implicit_known(p, f, sigma1, k, z, rng, point_landmarks=False)


def run_particle_filter(method, d, m, seed):
    """One run on data set d with M = m particles; returns the metrics of slam_common.metrics
    plus the mean ESS/M over the steps with an observation, the number of resamplings and the
    number of steps at which every particle failed (weights reset to equal)."""
    landmarks = load_landmarks()
    rng = np.random.default_rng(seed)
    p = Particles([d["x_true"][0], d["y_true"][0], d["beta_true"][0]], m, len(landmarks))
    seen = np.zeros(len(landmarks), bool)
    log_w, w = np.zeros(m), np.full(m, 1.0 / m)
    w_map, mu_map = w, p.mu
    steps = len(d["n"]) - 1
    path = np.empty((steps, 2))
    ess_sum, weighted, resamplings, degenerate = 0.0, 0, 0, 0
    for n in range(1, steps + 1):
        f, sigma1 = predict(p.x, d["vc"][n], d["alpha"][n])
        if d["has_obs"][n] < 0.5:
            p.x = draw(f, np.linalg.cholesky(sigma1), rng)
            path[n - 1] = w @ p.x[:, :2]
            continue
        k, z = int(d["landmark"][n]), np.array([d["z_r"][n], d["z_b"][n]])
        inc = update(method, p, f, sigma1, k, z, not seen[k], rng)
        log_w = log_w + np.where(np.isnan(inc), -np.inf, inc)
        seen[k] = True
        if np.isfinite(log_w).any():
            w = np.exp(log_w - log_w.max())
            w /= w.sum()
        else:  # every particle failed: start again from equal weights, and count it
            w = np.full(m, 1.0 / m)
            degenerate += 1
        with np.errstate(divide="ignore"):
            log_w = np.log(w)
        ess = 1.0 / (w**2).sum()
        ess_sum += ess / m
        weighted += 1
        path[n - 1] = w @ p.x[:, :2]  # the estimate uses the weights before resampling
        w_map, mu_map = w, p.mu
        if ess < m / 2:
            p.take(systematic_resample(w, rng))  # fancy indexing copies: mu_map is kept
            w, log_w = np.full(m, 1.0 / m), np.zeros(m)
            resamplings += 1
    out = metrics(path, d, np.einsum("m,mkj->kj", w_map, mu_map), landmarks, seen)
    out.update(ess_mean=ess_sum / max(weighted, 1), resamplings=resamplings,
               degenerate_steps=degenerate)
    return out


def run_ekf(d):
    """EKF-SLAM (spec §3.5): Joseph-form updates, augmentation at the first sighting, zero initial
    pose covariance. Returns the metrics and the (N, 3) pose trace."""
    landmarks = load_landmarks()
    x = np.array([d["x_true"][0], d["y_true"][0], d["beta_true"][0]])
    cov = np.zeros((3, 3))
    slot = {}
    steps = len(d["n"]) - 1
    trace = np.empty((steps, 3))
    for n in range(1, steps + 1):
        vc, alpha = d["vc"][n], d["alpha"][n]
        f, sigma1 = predict(x[None, :3], vc, alpha)
        fx = predict_jacobian(x[None, :3], vc, alpha)[0]
        x[:3] = f[0]
        cov[:3, :] = fx @ cov[:3, :]
        cov[:, :3] = cov[:, :3] @ fx.T
        cov[:3, :3] += sigma1[0]
        if d["has_obs"][n] > 0.5:
            k, z = int(d["landmark"][n]), np.array([d["z_r"][n], d["z_b"][n]])
            if k not in slot:
                m, gx, gz = place(x[None, :3], z)
                cross = gx[0] @ cov[:3, :]
                new = gx[0] @ cov[:3, :3] @ gx[0].T + gz[0] @ SIGMA2 @ gz[0].T
                slot[k] = len(x)
                x = np.concatenate([x, m[0]])
                cov = np.block([[cov, cross.T], [cross, new]])
            else:
                i = slot[k]
                e, dx, dy, r = residual(x[None, :3], x[None, i:i + 2], z)
                hx, hm = jacobians(dx, dy, r)
                hfull = np.zeros((2, len(x)))
                hfull[:, :3], hfull[:, i:i + 2] = hx[0], hm[0]
                s = hfull @ cov @ hfull.T + SIGMA2
                gain = cov @ hfull.T @ np.linalg.inv(s)
                x = x - gain @ e[0]
                a = np.eye(len(x)) - gain @ hfull
                cov = a @ cov @ a.T + gain @ SIGMA2 @ gain.T
                cov = 0.5 * (cov + cov.T)
        trace[n - 1] = x[:3]
    seen = np.zeros(len(landmarks), bool)
    est = np.zeros_like(landmarks)
    for k, i in slot.items():
        seen[k], est[k] = True, x[i:i + 2]
    out = metrics(trace[:, :2], d, est, landmarks, seen)
    out.update(ess_mean=None, resamplings=None)
    return out, trace

