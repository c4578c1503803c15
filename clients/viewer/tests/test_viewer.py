"""The viewer at `GET /` in a real headless Chromium, against a live `winged serve
--memory --demo`: it loads cleanly, draws the demo table, follows drags and the change
stream, picks bodies, runs the spatial query, and works with a read-only token."""

from __future__ import annotations

import base64
import io
import os
import time

import httpx
import numpy as np
import pytest
from conftest import Server, wait_for
from PIL import Image
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys

#: The shaded pictures' background colour (the server's default for `shaded`).
SHADED_BACKGROUND = np.array([200, 210, 225])


def open_viewer(browser, base: str, query: str = "") -> None:
    """Loads the viewer and waits for its first picture."""
    browser.get(f"{base}/{query}")
    wait_for(
        lambda: browser.execute_script(
            "return !!(window.wingedViewer && wingedViewer.ready && wingedViewer.frames > 0)"
        ),
        timeout=20,
        what="the viewer's first picture",
    )


def severe_logs(browser) -> list[dict]:
    """The browser console's errors since the last call."""
    return [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]


def canvas_pixels(browser, element_id: str) -> np.ndarray:
    """A canvas's pixels as an H × W × 4 array."""
    url = browser.execute_script(f"return document.getElementById('{element_id}').toDataURL('image/png')")
    data = base64.b64decode(url.split(",", 1)[1])
    return np.array(Image.open(io.BytesIO(data)).convert("RGBA"))


def frames(browser) -> int:
    """Pictures the viewer has painted."""
    return browser.execute_script("return wingedViewer.frames")


def body_id(base: str, name: str, headers: dict | None = None) -> int:
    """The id of the body called `name`."""
    r = httpx.get(f"{base}/v1/bodies", params={"name": name}, headers=headers or {})
    r.raise_for_status()
    (body,) = r.json()["bodies"]
    return body["id"]


def server_ids(base: str, camera: dict, headers: dict | None = None) -> tuple[np.ndarray, dict[int, int]]:
    """The server's ids picture for `camera`: the 16-bit values and the legend
    (body id → value)."""
    r = httpx.post(
        f"{base}/v1/appearance",
        json={"camera": camera, "mode": "ids", "format": "png"},
        headers=headers or {},
        timeout=30,
    )
    r.raise_for_status()
    values = np.array(Image.open(io.BytesIO(r.content))).astype(np.int64)
    legend = {}
    for pair in r.headers["X-Body-Ids"].split(","):
        value, ident = pair.split("=")
        legend[int(ident)] = int(value)
    return values, legend


def inner_pixel(mask: np.ndarray) -> tuple[int, int]:
    """A pixel (u, v) well inside a mask: the covered pixel farthest from any uncovered
    one (by repeated erosion)."""
    assert mask.any(), "the body is not in view"
    m = mask.copy()
    while True:
        eroded = m.copy()
        eroded[1:, :] &= m[:-1, :]
        eroded[:-1, :] &= m[1:, :]
        eroded[:, 1:] &= m[:, :-1]
        eroded[:, :-1] &= m[:, 1:]
        eroded[0, :] = eroded[-1, :] = False
        eroded[:, 0] = eroded[:, -1] = False
        if not eroded.any():
            break
        m = eroded
    vs, us = np.nonzero(m)
    i = len(vs) // 2
    return int(us[i]), int(vs[i])


def click_at(browser, u: int, v: int, shift: bool = False) -> None:
    """Clicks picture pixel (u, v) on the overlay (offsets count from the element's centre)."""
    overlay = browser.find_element(By.ID, "overlay")
    w = browser.execute_script("return document.getElementById('overlay').clientWidth")
    h = browser.execute_script("return document.getElementById('overlay').clientHeight")
    actions = ActionChains(browser).move_to_element_with_offset(overlay, u - w // 2, v - h // 2)
    actions = actions.key_down(Keys.SHIFT).click().key_up(Keys.SHIFT) if shift else actions.click()
    actions.perform()


def property_shown(browser, field: str) -> str:
    """The text of one row of the properties panel ("" when absent)."""
    found = browser.find_elements(By.CSS_SELECTOR, f'#properties dd[data-field="{field}"]')
    return found[0].text if found else ""


def test_the_page_loads_cleanly_and_shows_the_table(browser, server: Server):
    open_viewer(browser, server.base)
    errors = severe_logs(browser)
    assert errors == [], f"console errors: {errors}"
    assert browser.execute_script("return wingedViewer.errors") == 0, browser.find_element(By.ID, "message").text

    camera = browser.execute_script("return wingedViewer.camera()")
    ids, legend = server_ids(server.base, camera)
    table = body_id(server.base, "table")
    assert table in legend, f"the table is not in view: {legend}"
    table_mask = ids == legend[table]

    picture = canvas_pixels(browser, "picture")[:, :, :3].astype(np.int64)
    assert picture.shape[:2] == ids.shape, (picture.shape, ids.shape)
    not_background = np.abs(picture - SHADED_BACKGROUND).sum(axis=2) > 6
    assert not_background[table_mask].mean() > 0.95, "the table's pixels are drawn"
    assert not not_background[ids == 0].mean() > 0.05, "the background is the background"
    assert table_mask.mean() > 0.05, "the table fills a good part of the picture"

    # The parts tree lists the table with its legs and blocks under it.
    parts = browser.find_element(By.ID, "parts").text
    for name in ("table", "leg1", "cube", "wedge", "pyramid", "drum"):
        assert name in parts, parts
    cameras = browser.find_element(By.ID, "cameras").text
    assert "eye" in cameras and "Look through" in cameras, cameras
    assert "sun" in browser.find_element(By.ID, "lights").text
    wait_for(lambda: browser.find_element(By.ID, "stream").text == "changes: live", what="the change stream")


def test_a_drag_orbits_and_changes_the_picture(browser, server: Server):
    open_viewer(browser, server.base)
    before = canvas_pixels(browser, "picture")
    camera_before = browser.execute_script("return wingedViewer.camera()")
    count = frames(browser)
    overlay = browser.find_element(By.ID, "overlay")
    ActionChains(browser).move_to_element(overlay).click_and_hold().move_by_offset(40, 0).move_by_offset(
        40, 10
    ).move_by_offset(40, 10).release().perform()
    wait_for(
        lambda: browser.execute_script("return wingedViewer.camera()") != camera_before and frames(browser) > count,
        what="a picture of the moved camera",
    )
    # The last picture asked for (the newest view) is the one that ends up on screen.
    wait_for(lambda: not np.array_equal(canvas_pixels(browser, "picture"), before), what="the picture to change")
    after = browser.execute_script("return wingedViewer.camera()")
    assert after["look_at"]["eye"] != camera_before["look_at"]["eye"]
    assert after["look_at"]["target"] == camera_before["look_at"]["target"], "orbiting keeps the target"

    # The wheel zooms: the eye comes nearer the target.
    def distance(c):
        return float(np.linalg.norm(np.subtract(c["look_at"]["eye"], c["look_at"]["target"])))

    ActionChains(browser).scroll_from_origin(ScrollOrigin.from_element(overlay), 0, -300).perform()
    wait_for(
        lambda: distance(browser.execute_script("return wingedViewer.camera()")) < distance(after) - 1e-6,
        what="the wheel to zoom in",
    )
    assert severe_logs(browser) == []


def test_a_body_created_over_http_appears_within_a_second(browser, server: Server):
    open_viewer(browser, server.base)
    wait_for(lambda: browser.find_element(By.ID, "stream").text == "changes: live", what="the change stream")
    before = canvas_pixels(browser, "picture")
    count = frames(browser)
    started = time.monotonic()
    r = httpx.post(
        f"{server.base}/v1/bodies",
        json={
            "name": "visitor",
            "shape": {"type": "box", "size": [0.3, 0.3, 0.3]},
            "pose": {"position": [0.0, 0.0, 1.1]},
            "color": "#e02020",
        },
    )
    assert r.status_code == 201, r.text
    created = r.json()["id"]

    def shown() -> bool:
        listed = f"visitor #{created}" in browser.find_element(By.ID, "parts").text
        return listed and frames(browser) > count and not np.array_equal(canvas_pixels(browser, "picture"), before)

    wait_for(shown, timeout=1.0, interval=0.02, what="the new body in the parts list and the picture")
    elapsed = time.monotonic() - started
    assert elapsed < 1.0, elapsed
    # The new red box is drawn: reddish pixels where the server's ids picture has it.
    camera = browser.execute_script("return wingedViewer.camera()")
    ids, legend = server_ids(server.base, camera)
    assert created in legend
    picture = canvas_pixels(browser, "picture")[:, :, :3].astype(np.int64)
    red = picture[ids == legend[created]]
    assert (red[:, 0] > red[:, 1] + 40).mean() > 0.8, "the box is drawn in its colour"
    r = httpx.delete(f"{server.base}/v1/bodies/{created}")
    assert r.status_code in (200, 204), r.text
    wait_for(lambda: "visitor" not in browser.find_element(By.ID, "parts").text, timeout=2, what="the body to go")
    assert severe_logs(browser) == []


def test_clicking_the_cube_selects_it_and_shows_its_properties(browser, server: Server, repo_root):
    open_viewer(browser, server.base)
    cube = body_id(server.base, "cube")
    camera = browser.execute_script("return wingedViewer.camera()")
    ids, legend = server_ids(server.base, camera)
    u, v = inner_pixel(ids == legend[cube])
    click_at(browser, u, v)
    wait_for(lambda: property_shown(browser, "id") == str(cube), what="the cube's id in the properties panel")
    assert property_shown(browser, "name") == "cube"
    assert property_shown(browser, "parent").startswith("table #")
    assert property_shown(browser, "counts") == "6 faces, 12 edges, 8 vertices"
    assert property_shown(browser, "volume") == "0.001 m³"
    assert browser.execute_script("return wingedViewer.selected") == cube
    selected = browser.find_element(By.CSS_SELECTOR, "#parts button.selected").text
    assert selected == f"cube #{cube}"
    # The viewer's own ids picture agrees with the server's, and the highlight is drawn.
    wait_for(lambda: browser.execute_script(f"return wingedViewer.idsAt({u}, {v})") == cube, what="the viewer's ids")
    overlay = canvas_pixels(browser, "overlay")
    highlighted = overlay[:, :, 3] > 0
    assert highlighted[ids == legend[cube]].mean() > 0.95
    assert not highlighted[ids != legend[cube]].any()

    # Selecting from the parts list works too.
    table = body_id(server.base, "table")
    browser.find_element(By.CSS_SELECTOR, f'#parts button[data-id="{table}"]').click()
    wait_for(lambda: property_shown(browser, "id") == str(table), what="the table's properties")

    # Shift-click: the spatial query about the cube's surface point lists the cube and
    # draws its clipped edges over the picture.
    browser.find_element(By.ID, "radius").clear()
    browser.find_element(By.ID, "radius").send_keys("0.12")
    click_at(browser, u, v, shift=True)
    wait_for(
        lambda: f"cube #{cube}" in browser.find_element(By.ID, "query-results").text,
        what="the cube among the query's bodies",
    )
    centre = browser.find_element(By.ID, "query-centre").text
    assert "from the depth picture" in centre and "clipped edges" in centre, centre
    overlay = canvas_pixels(browser, "overlay")
    cyan = (overlay[:, :, 2] > 200) & (overlay[:, :, 1] > 150) & (overlay[:, :, 0] < 80) & (overlay[:, :, 3] > 200)
    assert cyan.sum() > 50, "the clipped edges are drawn"

    # Looking through the stored camera gives back the demo's view.
    browser.find_element(By.CSS_SELECTOR, '#cameras button[data-camera="eye"]').click()
    wait_for(
        lambda: np.allclose(browser.execute_script("return wingedViewer.camera()")["look_at"]["eye"], [1.6, -1.8, 1.7]),
        what="the camera eye's position",
    )
    shot = os.environ.get("WINGED_VIEWER_SCREENSHOT")
    if shot:
        pyramid = body_id(server.base, "pyramid")
        browser.find_element(By.CSS_SELECTOR, f'#parts button[data-id="{pyramid}"]').click()
        time.sleep(1.0)
        browser.execute_script("document.querySelector('aside').scrollTop = 0")
        path = repo_root / shot
        path.parent.mkdir(parents=True, exist_ok=True)
        assert browser.save_screenshot(str(path)), f"could not write {path}"
    assert severe_logs(browser) == []


def test_with_a_read_token_the_viewer_works_and_writes_are_refused(browser, token_server: Server):
    base = token_server.base
    browser.get(f"{base}/")
    # Without a token the page says what is wrong.
    wait_for(lambda: "401" in browser.find_element(By.ID, "message").text, what="the 401 message")
    assert "token" in browser.find_element(By.ID, "message").text
    severe_logs(browser)  # the refused requests are logged by the browser; start afresh

    browser.find_element(By.ID, "token").send_keys(token_server.read_token)
    browser.find_element(By.CSS_SELECTOR, "#token-form button[type=submit]").click()
    wait_for(
        lambda: browser.execute_script("return wingedViewer.ready && wingedViewer.frames > 0"),
        timeout=20,
        what="a picture with the read token",
    )
    assert browser.execute_script("return sessionStorage.getItem('winged.viewer.token')") == token_server.read_token
    wait_for(lambda: browser.find_element(By.ID, "stream").text == "changes: live", what="the change stream")
    picture = canvas_pixels(browser, "picture")[:, :, :3].astype(np.int64)
    assert (np.abs(picture - SHADED_BACKGROUND).sum(axis=2) > 6).mean() > 0.1, "the picture is drawn"

    read = {"Authorization": f"Bearer {token_server.read_token}"}
    write = {"Authorization": f"Bearer {token_server.write_token}"}
    shape = {"shape": {"type": "box", "size": [0.2, 0.2, 0.2]}, "pose": {"position": [0, 0, 1.1]}}
    refused = httpx.post(f"{base}/v1/bodies", json={**shape, "name": "nope"}, headers=read)
    assert refused.status_code == 403, refused.text

    # The stream follows writes made with another token.
    made = httpx.post(f"{base}/v1/bodies", json={**shape, "name": "guest"}, headers=write)
    assert made.status_code == 201, made.text
    wait_for(lambda: "guest" in browser.find_element(By.ID, "parts").text, timeout=1.0, what="the new body")

    # Picking works with the read token.
    cube = body_id(base, "cube", read)
    camera = browser.execute_script("return wingedViewer.camera()")
    ids, legend = server_ids(base, camera, read)
    u, v = inner_pixel(ids == legend[cube])
    click_at(browser, u, v)
    wait_for(lambda: property_shown(browser, "id") == str(cube), what="the cube's properties")
    assert "error" not in browser.find_element(By.ID, "message").get_attribute("class")
    assert severe_logs(browser) == []


@pytest.mark.parametrize("mode", ["wire", "hidden", "depth", "ids"])
def test_every_mode_draws(browser, server: Server, mode: str):
    open_viewer(browser, server.base)
    before = canvas_pixels(browser, "picture")
    count = frames(browser)
    browser.execute_script(
        "const s = document.getElementById('mode'); s.value = arguments[0];s.dispatchEvent(new Event('change'));",
        mode,
    )
    wait_for(lambda: frames(browser) > count, what=f"a {mode} picture")
    after = canvas_pixels(browser, "picture")
    assert not np.array_equal(before, after)
    # Not one flat colour.
    assert len(np.unique(after[:, :, :3].reshape(-1, 3), axis=0)) > 1
    assert severe_logs(browser) == []


#: Wraps fetch() in the page before its scripts run: records each change-stream
#: request's Last-Event-ID, ends the first stream right after its first change event
#: (as a dropped connection would), and holds the reconnection until the test releases it.
CUT_THE_STREAM = r"""
(() => {
  const original = window.fetch;
  const requests = [];
  let release;
  const released = new Promise((resolve) => { release = resolve; });
  window.__events = { requests, release: () => release() };
  window.fetch = async function (input, init) {
    const url = String(input instanceof Request ? input.url : input);
    if (!url.includes("/v1/world/events")) {
      return original.call(this, input, init);
    }
    const headers = new Headers(init && init.headers);
    requests.push({ url, lastEventId: headers.get("Last-Event-ID") });
    if (requests.length > 1) {
      await released;
      return original.call(this, input, init);
    }
    const res = await original.call(this, input, init);
    const reader = res.body.getReader();
    const decoder = new TextDecoder();
    let seen = "";
    const body = new ReadableStream({
      async pull(controller) {
        const { value, done } = await reader.read();
        if (done) {
          controller.close();
          return;
        }
        controller.enqueue(value);
        seen += decoder.decode(value, { stream: true });
        if (/event: ?change[^]*?\n\n/.test(seen)) {
          reader.cancel();
          controller.close();
        }
      },
    });
    return new Response(body, { status: res.status, headers: res.headers });
  };
})();
"""


def test_the_change_stream_resumes_with_last_event_id_after_a_drop(browser, server: Server):
    browser.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": CUT_THE_STREAM})
    open_viewer(browser, server.base)
    wait_for(lambda: browser.find_element(By.ID, "stream").text == "changes: live", what="the change stream")
    first = httpx.post(
        f"{server.base}/v1/bodies", json={"name": "first", "shape": {"type": "box", "size": [0.1, 0.1, 0.1]}}
    )
    assert first.status_code == 201, first.text
    wait_for(lambda: "first #" in browser.find_element(By.ID, "parts").text, timeout=2, what="the first body")
    # The stream was cut after that change; while the viewer is away, another write.
    wait_for(lambda: browser.execute_script("return __events.requests.length") == 2, what="the reconnection")
    second = httpx.post(
        f"{server.base}/v1/bodies", json={"name": "second", "shape": {"type": "box", "size": [0.1, 0.1, 0.1]}}
    )
    assert second.status_code == 201, second.text
    assert "second #" not in browser.find_element(By.ID, "parts").text
    browser.execute_script("__events.release()")
    wait_for(
        lambda: "second #" in browser.find_element(By.ID, "parts").text, timeout=2, what="the change made while away"
    )
    requests = browser.execute_script("return __events.requests")
    assert "since=" in requests[0]["url"] and requests[0]["lastEventId"] is None, requests
    assert requests[1]["lastEventId"] == str(first.json()["revision"]), requests
    assert "since=" not in requests[1]["url"], requests
    wait_for(lambda: browser.find_element(By.ID, "stream").text == "changes: live", what="the stream live again")
    for made in (first, second):
        httpx.delete(f"{server.base}/v1/bodies/{made.json()['id']}").raise_for_status()
    assert severe_logs(browser) == []


#: Counts the picture requests in flight at once, before the page's scripts run.
COUNT_PICTURE_REQUESTS = r"""
(() => {
  const original = window.fetch;
  const seen = { inFlight: 0, most: 0, sent: 0 };
  window.__pictures = seen;
  window.fetch = async function (input, init) {
    const url = String(input instanceof Request ? input.url : input);
    if (!url.includes("/v1/appearance")) {
      return original.call(this, input, init);
    }
    seen.sent += 1;
    seen.inFlight += 1;
    seen.most = Math.max(seen.most, seen.inFlight);
    try {
      const res = await original.call(this, input, init);
      await res.clone().arrayBuffer();
      return res;
    } finally {
      seen.inFlight -= 1;
    }
  };
})();
"""


def test_one_picture_request_at_a_time_and_the_newest_view_wins(browser, server: Server):
    browser.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": COUNT_PICTURE_REQUESTS})
    open_viewer(browser, server.base)
    browser.set_script_timeout(30)
    # The camera moves far more often than pictures can come.
    result = browser.execute_async_script("wingedViewer.spin(1500, 0.5, true).then(arguments[arguments.length - 1])")
    assert result["ticks"] > result["frames"] > 5, result
    wait_for(
        lambda: (
            browser.execute_script("return wingedViewer.camera()")
            == browser.execute_script("return wingedViewer.viewCamera()")
        ),
        what="the newest view on screen",
    )
    seen = browser.execute_script("return __pictures")
    assert seen["most"] == 1, seen
    assert seen["sent"] < result["ticks"], "views that were overtaken were never sent"
    assert severe_logs(browser) == []
