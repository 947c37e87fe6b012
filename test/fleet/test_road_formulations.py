"""scripts/road_formulations.py: its exact pieces against brute force and
closed forms, and a quick run's coverage (docs/studies/road_free_formulations.md)."""
import math

import numpy as np
import pytest

import road_formulations as rf


@pytest.fixture(scope="module")
def drive():
    """A 2 s drive over ISO C at 54 km/h, 280 kg."""
    road = rf.Road("C", 54.0, seed=3, seconds=2.0)
    return rf.Record(road, 280.0, seed=3)


def test_road_sinusoids_carry_the_iso_variance():
    # Waviness 2: sum Gd(n) dn over log bands at their geometric centres is
    # Gd(n0) n0^2 (1/n_min - 1/n_max), the band's integral.
    n, amp, _ = rf.iso_road("B", np.random.default_rng(0))
    expected = 64e-6 * 0.01 * (1.0 / rf.N_MIN - 1.0 / rf.N_MAX)
    assert (amp ** 2 / 2.0).sum() == pytest.approx(expected, rel=1e-12)
    assert n[0] > rf.N_MIN and n[-1] < rf.N_MAX


def test_truth_obeys_the_body_equation_and_v_is_the_rate_of_u(drive):
    mass = rf.M_BODY + 0.5 * drive.load
    for zero, static in (("tare", rf.M_BODY * rf.GRAVITY), ("rest", 0.0)):
        u, v, a = drive.with_zero(zero).clean.T
        np.testing.assert_allclose(a, (static - rf.SPRING * u - rf.DAMPER * v) / mass,
                                   rtol=0, atol=1e-10)
    # Per sinusoid, v's coefficient is i omega times u's.
    c = rf.road_coefficients(np.array([mass]), rf.SPRING, drive.road.omega, drive.road.amp)[0]
    f = drive.road.omega.size
    u_c, v_c = c[0, :f] + 1j * c[0, f:], c[1, :f] + 1j * c[1, f:]
    np.testing.assert_allclose(v_c, 1j * drive.road.omega * u_c, rtol=1e-10, atol=1e-15)
    # The load's sag is in tare's travel: M g / (2 k) below rest's.
    sag = drive.with_zero("rest").clean[:, 0] - drive.with_zero("tare").clean[:, 0]
    np.testing.assert_allclose(sag, 140.0 * rf.GRAVITY / rf.SPRING, rtol=1e-12)


def dense_loglik(f, qd, h, d, r, p0, y):
    """log N(y; d, Sigma) of the stacked readings, Sigma built sample by sample
    from the stationary state covariance: Cov(x_i, x_j) = F^(i-j) P0."""
    t, p = y.shape
    n = f.shape[0]
    powers = [np.eye(n)]
    for _ in range(t):
        powers.append(f @ powers[-1])
    sigma = np.zeros((t * p, t * p))
    for i in range(t):
        for j in range(i + 1):
            block = h @ powers[i - j] @ p0 @ h.T + (r if i == j else 0.0)
            sigma[i * p:(i + 1) * p, j * p:(j + 1) * p] = block
            sigma[j * p:(j + 1) * p, i * p:(i + 1) * p] = block.T
    e = (y - d).ravel()
    sign, logdet = np.linalg.slogdet(sigma)
    assert sign > 0
    return -0.5 * (logdet + e @ np.linalg.solve(sigma, e) + e.size * math.log(2.0 * math.pi))


@pytest.mark.parametrize("corner", [0.0, 0.02])
@pytest.mark.parametrize("zero", ["tare", "rest"])
def test_kalman_innovations_give_the_dense_gaussian_loglik(drive, corner, zero):
    y = drive.with_zero(zero).y[:30]
    m = np.array([230.0, 280.0])
    f, qd, h, d, r, p0 = rf.road_state_model(m, zero, rf.ROUGHNESS["C"], drive.road.speed, corner)
    gains = rf.kalman_gains(f, qd, h, r, p0, y.shape[0])
    ll, chi2 = rf.kalman_loglik(f, h, d, y, gains)
    for g in range(m.size):
        dense = dense_loglik(f[g], qd[g], h[g], d[g], r, p0[g], y)
        assert ll[g] == pytest.approx(dense, abs=1e-7)
    # The truth's load is the likelier one.
    assert ll[1] > ll[0]


def test_stationary_covariance_and_road_variance():
    # P0 = F P0 F' + Q, and with a corner the road's variance is q / (2 alpha).
    m = np.array([250.0])
    f, qd, _, _, _, p0 = rf.road_state_model(m, "rest", 64e-6, 10.0, corner=0.02)
    np.testing.assert_allclose(f[0] @ p0[0] @ f[0].T + qd[0], p0[0], rtol=1e-9, atol=1e-18)
    q = 2.0 * math.pi ** 2 * 64e-6 * 0.01 * 10.0
    assert p0[0, 4, 4] == pytest.approx(q / (2.0 * 2.0 * math.pi * 0.02 * 10.0), rel=1e-9)


@pytest.mark.parametrize("corner", [0.0, 0.5])
def test_stationary_readings_match_the_road_spectrum(corner):
    # var of u, v, a from P0 against the integral of |Y(i w)|^2 times the
    # road's one-sided PSD, ISO 8608's Gd(n0) n0^2 V / f^2 flattened below
    # the corner frequency n_c V (a wide corner, so the shaping matters).
    speed, mass = 10.0, 250.0
    _, _, h, _, _, p0 = rf.road_state_model(np.array([mass]), "rest", 64e-6, speed, corner)
    model = np.diag(h[0] @ p0[0] @ h[0].T)
    a, b = rf.quarter_car(np.array([rf.M_BODY + 0.5 * mass]), rf.SPRING)
    freq = np.logspace(-5, 5, 40001)
    w = 2.0 * math.pi * freq
    x = np.linalg.solve(1j * w[:, None, None] * np.eye(4) - a[0], np.broadcast_to(b, (w.size, 4)))
    y = x @ rf.reading_rows(a)[0].T  # (F,3)
    road_psd = 64e-6 * 0.01 * speed / (freq ** 2 + (corner * speed) ** 2)
    psd = np.abs(y) ** 2 * road_psd[:, None]
    integral = np.trapz(psd * freq[:, None], np.log(freq), axis=0)
    np.testing.assert_allclose(model, integral, rtol=1e-4)


def test_fitted_roughness_finds_the_road_class():
    # Told nothing about the road, the marginal likelihood finds ISO C's
    # Gd(n0) = 256e-6 m^3 within 15 %, far from the neighbouring classes (x4).
    road = rf.Road("C", 54.0, seed=4, seconds=10.0)
    rec = rf.Record(road, 150.0, seed=4).with_zero("rest")
    assert rf.fitted_roughness(rec, road.speed, 150.0) / 256e-6 == pytest.approx(1.0, abs=0.15)


def test_base_excitation_on_noise_free_inputs_is_least_squares():
    # With exact u, v the model a = F / m + noise is linear in 1/m: the
    # likelihood's mean and std are the least-squares mass and its spread.
    road = rf.Road("B", 36.0, seed=5, seconds=2.0)
    rec = rf.Record(road, 150.0, seed=5, std=(0.0, 0.0, 0.03)).with_zero("rest")
    u, v, a = rec.y.T
    force = -rf.SPRING * u - rf.DAMPER * v
    inv = (a * force).sum() / (force ** 2).sum()
    m_ls = 2.0 * (1.0 / inv - rf.M_BODY)
    std_ls = 2.0 * 0.03 / math.sqrt((force ** 2).sum()) / inv ** 2
    mean, std, chi2, dof = rf.grid_posterior(rf.base_excitation(rec), prior=False)
    assert std == pytest.approx(std_ls, rel=0.02)
    assert abs(mean - m_ls) < 0.02 * std
    assert dof == 400 and not rf.flagged(chi2, dof)


def test_errors_in_variables_variance_is_the_residuals():
    # With the rate 10x noisier than the sensor's, the residuals at the true
    # load have the variance sigma_a^2 + (k^2 sigma_u^2 + c^2 sigma_v^2) / m^2:
    # their chi-square passes with it and fails without it.
    road = rf.Road("C", 54.0, seed=2, seconds=10.0)
    rec = rf.Record(road, 280.0, seed=2, std=(5e-4, 0.05, 0.03))
    for zero in ("tare", "rest"):
        _, chi2, dof = rf.base_excitation(rec.with_zero(zero))(np.array([280.0]))
        assert not rf.flagged(chi2[0], dof)
        _, chi2, dof = rf.base_excitation(rec.with_zero(zero), eiv=False)(np.array([280.0]))
        assert rf.flagged(chi2[0], dof)


def test_travel_blend_passes_agreeing_readings_and_cuts_the_noise():
    t = np.arange(400) / rf.RATE
    u = 0.01 * np.sin(2.0 * math.pi * t)
    v = 0.01 * 2.0 * math.pi * np.cos(2.0 * math.pi * t)
    np.testing.assert_allclose(rf.travel_blend(u, v), u, atol=2e-6)
    noise = np.random.default_rng(4).standard_normal((2, 200000)) * np.array([[5e-4], [5e-3]])
    blended = rf.travel_blend(noise[0], noise[1])[1000:]
    assert blended.std() == pytest.approx(rf.blend_std(5e-4, 5e-3), rel=0.02)


def test_chi_square_bounds():
    # Tables: chi-square(100) 0.5 % and 99.5 % points 67.328 and 140.169.
    low, high = rf.chi2_bounds(100)
    assert low == pytest.approx(67.328, rel=1e-3) and high == pytest.approx(140.169, rel=1e-3)
    assert rf.flagged(150.0, 100) and not rf.flagged(100.0, 100) and rf.flagged(60.0, 100)


def test_quick_drive_covers_and_a_flat_road_does_not(drive):
    tare, rest = drive.with_zero("tare"), drive.with_zero("rest")
    for rec, make in ((tare, rf.base_excitation), (rest, rf.base_excitation),
                      (tare, rf.road_as_state), (rest, rf.road_as_state),
                      (tare, lambda r: rf.road_given(r, 1.0))):
        mean, std, chi2, dof = rf.grid_posterior(make(rec))
        assert abs(mean - 280.0) < 3.0 * std and not rf.flagged(chi2, dof)
    # Told a flat road, the travel's dynamics read as a sag: far off and flagged.
    mean, std, chi2, dof = rf.grid_posterior(rf.road_given(tare, 0.0))
    assert abs(mean - 280.0) > 3.0 * std and rf.flagged(chi2, dof)
    # Ignoring the inputs' noise makes a's residuals too large for sigma_a.
    assert rf.flagged(*rf.grid_posterior(rf.base_excitation(tare, eiv=False))[2:])


def test_rest_carries_no_static_information():
    # Told a flat road with zero rest, nothing depends on M: the prior comes back.
    road = rf.Road("B", 36.0, seed=1, seconds=1.0)
    rec = rf.Record(road, 150.0, seed=1).with_zero("rest")
    mean, std, _, _ = rf.grid_posterior(rf.road_given(rec, 0.0))
    assert mean == pytest.approx(200.0, abs=1e-9)
    # Beta(2,2): xi has variance 1/5 (41 points: the trapezoid rule within 0.2 %)
    assert std == pytest.approx(100.0 / math.sqrt(5.0), rel=2e-3)
