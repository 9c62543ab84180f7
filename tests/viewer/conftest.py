"""Small blocks and a local viser server for the viewer tests."""

import numpy as np
import pytest

import orientviz as ov


def tiny_block(rng: np.random.Generator, noise_mm: float = 0.0) -> ov.Block:
    """Two strips of three vertical images over a 5 × 4 grid of points (4 control)."""
    c, H = 152.0, 1520.0
    X0 = np.array([[x, y, H] for y in (0.0, 1000.0) for x in (0.0, 900.0, 1800.0)])
    X0[:, :2] += rng.normal(0, 5.0, (6, 2))
    angles = rng.normal(0, 0.005, (6, 3))
    gx, gy = np.meshgrid(np.linspace(-300, 2100, 5), np.linspace(-300, 1300, 4))
    xyz = np.column_stack([gx.ravel(), gy.ravel(), rng.uniform(0, 80, gx.size)])
    R = ov.matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2])
    oi, op, xy = [], [], []
    for i in range(6):
        p = ov.project(xyz, X0[i], R[i], c)
        ok = np.all(np.abs(p) < 110.0, axis=1)
        oi += [i] * int(ok.sum())
        op += list(np.flatnonzero(ok))
        xy.append(p[ok])
    xy = np.vstack(xy) + rng.normal(0, noise_mm, (len(oi), 2)) if noise_mm else np.vstack(xy)
    role = np.zeros(len(xyz), int)
    role[[0, 4, 15, 19]] = 1
    role[9] = 2
    return ov.Block.from_arrays(
        camera_c=[c], image_camera=np.zeros(6, int), X0=X0, angles=angles, xyz=xyz,
        obs_image=oi, obs_point=op, obs_xy=xy, role=role, strip=[0, 0, 0, 1, 1, 1],
    )  # fmt: skip


@pytest.fixture
def block():
    return tiny_block(np.random.default_rng(5))


@pytest.fixture
def server():
    viser = pytest.importorskip("viser")
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


@pytest.fixture(scope="module")
def module_browser(request):
    """One headless Chromium for a whole test module (playwright's browser context);
    each test opens its pages with ``module_browser.new_page()``. Same executable and
    flags as the ``browser_page`` fixture of tests/conftest.py."""
    import os
    import shutil
    import tempfile

    chromium = os.environ.get("ORIENTVIZ_CHROMIUM", "/usr/bin/chromium")
    if not os.path.exists(chromium):
        pytest.skip(f"no Chromium at {chromium} (apt-get install -y chromium chromium-driver)")
    sync_api = pytest.importorskip("playwright.sync_api")
    flags = request.config.pluginmanager.get_plugin(
        os.path.join(str(request.config.rootpath), "tests", "conftest.py")
    )
    args = getattr(flags, "CHROMIUM_FLAGS", None) or [
        "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
    ]  # fmt: skip
    profile = tempfile.mkdtemp(prefix="orientviz-chromium-")
    with sync_api.sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            profile, executable_path=chromium, headless=True, args=args,
            viewport={"width": 1280, "height": 800}, accept_downloads=True,
        )  # fmt: skip
        try:
            yield context
        finally:
            context.close()
            shutil.rmtree(profile, ignore_errors=True)
