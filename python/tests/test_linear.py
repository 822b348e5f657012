"""Linear stability data (fixed_point(jacobian=True), lyapunov) against independent references:
central differences of the stride map, the eigen-equation, the multipliers, the closed-form
impact map of Garcia et al. 1998."""

import numpy as np
import pytest

import pdw_sweep as pdw


def gait(model="simplest", slope=0.009):
    return pdw.fixed_point(model, slope=slope, gait="stable", jacobian=True)[0]


def central(model, slope, s, h):
    """Central differences of the stride map at s with step h (columns: d/ds_j)."""
    n = len(s)
    pts = np.array([s + sgn * h * np.eye(n)[j] for j in range(n) for sgn in (1, -1)])
    nxt, codes, _ = pdw.stride_map(model, pts, slope=slope)
    assert np.all(codes == 13)  # heel_strike: every stride complete
    return np.array([(nxt[2 * j] - nxt[2 * j + 1]) / (2 * h) for j in range(n)]).T


def test_jacobian_equals_central_differences_of_the_stride_map():
    for model, slope in [("simplest", 0.009), ("compass", "3deg")]:
        fp = gait(model, slope)
        s = fp["section"]
        # Richardson's extrapolation of two central differences: error O(h^4)
        h = 1e-4
        fd = (4 * central(model, slope, s, h / 2) - central(model, slope, s, h)) / 3
        np.testing.assert_allclose(fp["jacobian"], fd, rtol=0, atol=1e-6 * max(1, abs(fd).max()))


def test_eigenpairs_satisfy_the_eigen_equation_and_are_the_multipliers():
    for model, slope in [("simplest", 0.009), ("compass", "3deg")]:
        fp = gait(model, slope)
        dp, lam, v = fp["jacobian"], fp["eigenvalues"], fp["eigenvectors"]
        for k in range(len(lam)):
            assert np.linalg.norm(dp @ v[:, k] - lam[k] * v[:, k]) < 1e-9
            assert abs(np.linalg.norm(v[:, k]) - 1) < 1e-12
        np.testing.assert_allclose(np.sort_complex(lam), np.sort_complex(fp["multipliers"]),
                                   atol=1e-9)


def test_lyapunov_exponents_at_a_fixed_point_are_the_log_multipliers():
    fp = gait()
    want = np.sort(np.log(np.abs(fp["multipliers"])))[::-1]
    # the sum is ln|det DP| exactly (volume), the exponents converge as 1/N
    assert abs(fp["lyapunov"].sum() - want.sum()) < 1e-8
    exps = pdw.lyapunov("simplest", state=fp["section"], strides=2000, slope=0.009)
    np.testing.assert_allclose(exps, want, atol=5e-3)
    assert abs(exps.sum() - want.sum()) < 1e-8
    # default state: the stable gait
    np.testing.assert_allclose(pdw.lyapunov("simplest", strides=2000, slope=0.009), exps,
                               atol=1e-9)
    with pytest.raises(ValueError, match="state"):
        pdw.lyapunov("simplest", state=[0.2])


def test_saltation_of_the_heel_strike_is_garcias_closed_form():
    gamma = 0.009
    fp = gait("simplest", gamma)
    assert fp["state_names"] == ["theta", "thetadot", "phi", "phidot"]
    (imp,) = [i for i in fp["impacts"] if i["event"] == "heel_strike"]
    th, thd, ph, phd = imp["pre"]
    c, s2 = np.cos(2 * th), np.sin(2 * th)

    def f(x):  # Garcia et al. 1998, eq. 4
        a, ad, p, pd = x
        return np.array([ad, np.sin(a - gamma), pd,
                         np.sin(a - gamma) + (ad ** 2 - np.cos(a - gamma)) * np.sin(p)])

    post = np.array([-th, c * thd, -2 * th, c * (1 - c) * thd])   # the impact map, eq. 5
    dr = np.array([[-1, 0, 0, 0],
                   [-2 * s2 * thd, c, 0, 0],
                   [-2, 0, 0, 0],
                   [2 * s2 * (2 * c - 1) * thd, c * (1 - c), 0, 0]])
    grad = np.array([-2.0, 0, 1, 0])                                 # guard phi - 2 theta
    fm = f(imp["pre"])
    xi = dr + np.outer(f(post) - dr @ fm, grad) / (grad @ fm)
    np.testing.assert_allclose(imp["saltation"], xi, rtol=0, atol=1e-12)
    assert abs(imp["pre"][2] - 2 * imp["pre"][0]) < 1e-10


def test_jacobian_data_equal_the_cli_json():
    import json
    import subprocess

    from test_pdw_sweep import cli
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    args = [exe, "fixedpoint", "--model", "compass", "--gait", "stable", "--json"]
    plain = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    assert "linear" not in plain["fixed_points"][0]
    ref = json.loads(subprocess.run(args + ["--jacobian"], check=True, capture_output=True,
                                    text=True).stdout)
    (r,) = ref["fixed_points"]
    assert {k: v for k, v in r.items() if k != "linear"} == plain["fixed_points"][0]
    lin = r["linear"]
    fp = pdw.fixed_point("compass", gait="stable", jacobian=True)[0]
    np.testing.assert_array_equal(fp["jacobian"], lin["jacobian"])
    np.testing.assert_array_equal(fp["lyapunov"], lin["lyapunov"])
    np.testing.assert_array_equal(fp["eigenvalues"],
                                  [complex(z["re"], z["im"]) for z in lin["eigenvalues"]])
    vecs = np.array([[complex(z["re"], z["im"]) for z in v] for v in lin["eigenvectors"]]).T
    np.testing.assert_array_equal(fp["eigenvectors"], vecs)
    assert [i["event"] for i in fp["impacts"]] == [i["event"] for i in lin["impacts"]]
    for a, b in zip(fp["impacts"], lin["impacts"]):
        np.testing.assert_array_equal(a["saltation"], b["saltation"])


def test_gait_sensitivity_norm_is_the_impulse_response_of_its_matrices():
    # the norm from the returned A, B, C, D summed term by term (an independent route to the
    # Lyapunov solve): ||H_i||^2 = D_i^2 + sum_k (C_i A^(k-1) B)^2
    r = pdw.gait_sensitivity("simplest", slope=0.009)
    A, B, C, D = r["A"], r["B"], r["C"], r["D"]
    assert r["indicators"] == ["step-time", "step-length"]
    assert A.shape == (3, 3) and B.shape == (3, 1) and C.shape == (2, 3) and D.shape == (2, 1)
    sums = (D[:, 0] ** 2).copy()
    v = B.copy()
    for _ in range(400):
        sums += (C @ v)[:, 0] ** 2
        v = A @ v
    np.testing.assert_allclose(np.sqrt(sums), r["per_indicator"], rtol=1e-10)
    assert abs(np.sqrt(sums.sum()) - r["norm"]) <= 1e-10 * r["norm"]
    assert max(abs(np.linalg.eigvals(A))) == pytest.approx(r["spectral_radius"], rel=1e-12)
    assert r["fd_error"] < 1e-8


def test_gait_sensitivity_of_an_unstable_gait_and_a_bad_indicator_raise():
    with pytest.raises(ValueError, match="unstable"):
        pdw.gait_sensitivity("simplest", slope=0.009, guess=[0.1939, -0.2039])
    with pytest.raises(ValueError, match="hop"):
        pdw.gait_sensitivity("simplest", slope=0.009, indicators="step-time,hop")


def test_mfpt_over_draws_from_the_named_distribution_as_the_single_runs_do(tmp_path):
    r = pdw.mfpt_over("slope=0.03:0.05:2", model="compass", sd="1deg", walkers=30, max_strides=200, seed=2, dist="uniform")
    normal = pdw.mfpt_over("slope=0.03:0.05:2", model="compass", sd="1deg", walkers=30, max_strides=200, seed=2)
    assert r["dist"].startswith("uniform") and normal["dist"].startswith("normal")
    assert list(r["mfpt"]) != list(normal["mfpt"])
    values = tmp_path / "xi.txt"
    values.write_text("# two slopes\n-1\n1\n")
    f = pdw.mfpt_over("slope=0.03:0.05:2", model="compass", sd="1deg", walkers=30, max_strides=200, seed=2, dist=f"file:{values}")
    for i in (0, 1):
        one = pdw.mfpt(model="compass", slope=r["values"][i], sd="1deg", walkers=30, max_strides=200, seed=2, dist="uniform")
        assert one["mfpt"] == r["mfpt"][i]
        one = pdw.mfpt(model="compass", slope=f["values"][i], sd="1deg", walkers=30, max_strides=200, seed=2, dist=f"file:{values}")
        assert one["mfpt"] == f["mfpt"][i]
    with pytest.raises(ValueError, match="dist"):
        pdw.mfpt_over("slope=0.03:0.05:2", model="compass", sd="1deg", walkers=30, dist="cauchy")


def test_mfpt_over_is_the_single_runs_and_marks_values_without_a_gait():
    r = pdw.mfpt_over("slope=-0.02:0.06:3", model="compass", sd="1deg", walkers=30, max_strides=200, seed=2)
    assert list(r["values"]) == [-0.02, 0.02, 0.06]
    assert list(r["stable"]) == [False, True, True]
    assert np.isnan(r["mfpt"][0]) and np.isnan(r["gsn"][0])
    for i in (1, 2):
        one = pdw.mfpt(model="compass", slope=r["values"][i], sd="1deg", walkers=30, max_strides=200, seed=2)
        assert one["mfpt"] == r["mfpt"][i]
        g = pdw.gait_sensitivity("compass", slope=r["values"][i])
        assert g["norm"] == r["gsn"][i]
