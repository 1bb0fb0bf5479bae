"""The compiled whole-run simulation equals stepping DiscretePlant with the Compensator
in Python, sample by sample (ARCHITECTURE.md timing: sensors see x_k, v[k] from
theta[k-d], a[k-d] and u[k], then x_{k+1} = Ad x_k + Bd v[k])."""

import numpy as np
import pytest

from station.control import make_controller, step_reference
from station.plant import DiscretePlant, simulate
from station.plant.kernel import KernelEffects
import importlib

simulate_module = importlib.import_module("station.plant.simulate")

AMPLITUDE = {"p": 50.0, "lead": 100.0, "lead-accel": 200.0, "open-loop": 40.0}


def _python_run(plant, controller, u, d, quantize, v_open=None):
    plant.reset()
    controller.reset()
    rows = {key: [] for key in ("theta", "a", "v", "theta_d_hat")}
    for k in range(u.size):
        theta, a = plant.outputs()
        if quantize:
            theta, a = np.floor(theta + 0.5), np.floor(a + 0.5)
        rows["theta"].append(theta)
        rows["a"].append(a)
        if v_open is None and k < d:
            v, thd = 0.0, u[k]  # no sample yet: the device outputs 0
        elif v_open is None:
            v, thd = controller.step(u[k], rows["theta"][k - d], rows["a"][k - d])
        else:
            v, thd = v_open[k], u[k]
        rows["v"].append(v)
        rows["theta_d_hat"].append(thd)
        plant.advance(v)
    plant.reset()
    return {key: np.array(val) for key, val in rows.items()}


@pytest.fixture(scope="module", params=[1, 4, 100])
def plant(request):
    return DiscretePlant(n_elements=request.param)


@pytest.mark.parametrize("kind", ["p", "lead", "lead-accel", "open-loop"])
@pytest.mark.parametrize("d, quantize", [(1, True), (1, False), (0, True), (2, False)])
def test_kernel_equals_python_stepping(plant, kind, d, quantize):
    controller = make_controller(kind)
    u = step_reference(AMPLITUDE[kind], 1000, at_tick=10)
    plant.reset()
    fast = simulate(plant, controller, u, alignment=d, quantize=quantize)
    slow = _python_run(plant, controller, u, d, quantize)
    for key in slow:
        np.testing.assert_allclose(fast[key], slow[key], rtol=1e-9, atol=1e-9, err_msg=key)
    assert fast["t"] == pytest.approx(np.arange(1000) * 0.002)


def test_v_open_replays_the_given_command(plant):
    v = np.zeros(600)
    v[20:70], v[300:350] = 100.0, -100.0
    u = np.zeros(600)
    plant.reset()
    fast = simulate(plant, make_controller("lead"), u, v_open=v, quantize=False)
    theta, a = plant.simulate_open_loop(v)
    plant.reset()
    np.testing.assert_allclose(fast["v"], v)
    np.testing.assert_allclose(fast["theta"], theta, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fast["a"], a, rtol=1e-9, atol=1e-9)


def test_starts_from_current_state_and_leaves_it():
    plant = DiscretePlant(n_elements=4)
    plant.reset()
    for _ in range(50):
        plant.advance(100.0)
    x = plant.x.copy()
    u = np.zeros(200)
    fast = simulate(plant, make_controller("open-loop"), u, quantize=False)
    assert np.array_equal(plant.x, x)
    theta, _ = plant.simulate_open_loop(np.zeros(200))
    np.testing.assert_allclose(fast["theta"], theta, rtol=1e-9, atol=1e-9)


def test_plain_python_kernel_matches_compiled():
    # numba is a dependency: the kernel must be compiled (a plain _kernel = _loop would make
    # this test compare the loop with itself); its own Python source must give the same run
    from station.plant import kernel

    kernel._compile()  # numba is imported on first use (start-up time), then the loop is compiled
    assert hasattr(kernel._compiled_loop, "py_func"), "the sample loop is not numba-compiled"
    plant = DiscretePlant(n_elements=2)
    controller = make_controller("lead-accel")
    u = step_reference(200.0, 200, at_tick=10)
    lam, bm, cm, vinv = plant.modal_form()
    gnum, gden = simulate_module._coeffs(controller.gth)
    anum, aden = simulate_module._coeffs(controller.ga)
    n = lam.size
    args = (lam, bm, np.zeros(n, complex), np.ascontiguousarray(cm), np.zeros((4, n), complex), 0.0, 0.0, 0,
            np.zeros(n, complex), u, np.zeros(1), False, True,
            gnum, gden, anum, aden, True, 200.0, 1, True, 1, 2,  # command quantization: round; recursion on the truncated integer
            *KernelEffects())  # no effects
    plain = kernel._compiled_loop.py_func(*args)
    compiled = simulate_module._kernel(*args)
    for x, y in zip(plain, compiled):
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12)


def test_bad_arguments():
    plant = DiscretePlant(n_elements=1)
    with pytest.raises(ValueError, match="alignment"):
        simulate(plant, make_controller("p"), np.zeros(10), alignment=-1)
    with pytest.raises(ValueError, match="v_open"):
        simulate(plant, make_controller("p"), np.zeros(10), v_open=np.zeros(9))


def test_simulate_returns_a_named_result_that_unpacks_and_exports():
    plant = DiscretePlant()
    u = step_reference(50.0, 200, at_tick=10)
    run = simulate(plant, make_controller("p"), u)
    t, uu, v, theta, a, thd = run  # unpacks like a tuple, in this order
    assert run.theta is theta and run["theta"] is theta and "theta" in run and "nope" not in run
    assert np.array_equal(uu, u) and np.allclose(t, np.arange(200) * 0.002)
    df = run.to_pandas()
    assert list(df.columns) == ["t", "u", "v", "theta", "a", "theta_d_hat"] and len(df) == 200
    with pytest.raises(KeyError):
        run["nope"]


def test_the_simulated_rig_steps_in_plain_python_to_the_same_bits():
    # the device's plant of a small linear model steps in plain Python (no compiler at start-up);
    # the compiled functions are the independent check, sample for sample, effects included
    from station.plant.kernel import ModelPlant
    from station.plant.model import load_model

    rng = np.random.default_rng(5)
    commands = np.round(rng.uniform(-220.0, 220.0, 1500))
    for name in ("tmm-fit", "rig"):
        model = load_model(name)
        plain, compiled = ModelPlant(model, compiled=False), ModelPlant(model, compiled=True)
        for v in commands:
            assert plain.outputs() == compiled.outputs()
            plain.advance(v)
            compiled.advance(v)
    assert ModelPlant(load_model("tmm-fit"))._fns[2] is not ModelPlant(load_model("rig"))._fns[2]


@pytest.mark.parametrize("substeps, half_gap", [(0, 0.0), (10, 0.0), (10, 0.7)])
def test_the_modal_step_is_the_complex_recursion(substeps, half_gap):
    """The kernel writes z <- Λz + b_m·u + b_p·t as real products (complex × real without its
    products by zero): the same floats as the complex recursion, compiled and plain, on random
    modes (the Python loop below is the textbook form, not the kernel's)."""
    from station.plant import kernel

    kernel._compile()
    rng = np.random.default_rng(11)
    n = 13
    cplx = lambda *shape: rng.normal(size=shape) + 1j * rng.normal(size=shape)  # noqa: E731
    lam, bm, bp, co = cplx(n) * 0.9, cplx(n), cplx(n), cplx(4, n) * 0.1
    k_d, c_d = 0.3, 0.01
    for trial in range(50):
        z0, vk = cplx(n), float(rng.uniform(-200, 200))
        want = z0.copy()
        for _ in range(max(substeps, 1)):
            t = 0.0
            if substeps and half_gap > 0.0:
                dl = sum((co[0, i] * want[i]).real for i in range(n))
                ddl = sum((co[1, i] * want[i]).real for i in range(n))
                t = k_d * half_gap if dl > half_gap else -k_d * half_gap if dl < -half_gap else k_d * dl + c_d * ddl
            want = np.array([lam[i] * want[i] + bm[i] * vk + bp[i] * t if substeps else lam[i] * want[i] + bm[i] * vk
                             for i in range(n)])
        for advance in (kernel._PLAIN[2], kernel._advance):
            z = z0.copy()
            advance(z, vk, lam, bm, bp, co, 1.0, 0.0, substeps, 0.0, 0.0, 0.05, half_gap, k_d, c_d)
            assert np.array_equal(z, want), (trial, advance)
