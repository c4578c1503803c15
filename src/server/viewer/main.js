// The viewer: the world through an orbit camera as the server draws it, kept live by
// the change stream, with picking, the parts tree, stored cameras and lights, and a
// spatial query tool. This module holds the page's state and wires the others together.

import { getJson, getToken, setToken } from "./api.js";
import { WorldEvents } from "./events.js";
import { FrameLoop } from "./frames.js";
import { Orbit, attachControls } from "./orbit.js";
import { Overlay } from "./overlay.js";
import { renderCameras, renderLights, renderParts, renderProperties, renderQuery, vec, num } from "./panels.js";
import { IdsBuffer } from "./picking.js";
import { fetchPicture, paint } from "./picture.js";
import { pointUnder, shapeOf, sphereQuery } from "./spatial.js";
import { Status } from "./status.js";

/** The largest picture asked for, a side, so that a huge window does not flood the server. */
const MAX_SIDE = 2048;

/**
 * An element by id.
 * @template {HTMLElement} T
 * @param {string} id
 * @returns {T}
 */
function $(id) {
  const e = document.getElementById(id);
  if (!e) {
    throw new Error(`the page has no #${id}`);
  }
  return /** @type {T} */ (e);
}

const view = $("view");
const pictureCanvas = /** @type {HTMLCanvasElement} */ ($("picture"));
const pictureCtx = /** @type {CanvasRenderingContext2D} */ (pictureCanvas.getContext("2d"));
const overlayCanvas = /** @type {HTMLCanvasElement} */ ($("overlay"));
const modeSelect = /** @type {HTMLSelectElement} */ ($("mode"));
const shadowsBox = /** @type {HTMLInputElement} */ ($("shadows"));
const tokenInput = /** @type {HTMLInputElement} */ ($("token"));
const radiusInput = /** @type {HTMLInputElement} */ ($("radius"));
const status = new Status($("message"), $("stream"), $("stats"), $("error-log"));
const overlay = new Overlay(overlayCanvas);

/** Everything the page knows. */
const state = {
  orbit: new Orbit(),
  /** @type {Orbit | null} The view to go back to. */
  home: null,
  /** Picture size, pixels. */
  width: 640,
  height: 480,
  /** @type {{width: number, height: number} | null} A size fixed by `?size=WxH`, or null to fit the window. */
  fixedSize: null,
  /** The newest world revision known. */
  revision: 0,
  /** @type {any[]} */
  bodies: [],
  /** @type {Map<number, any>} */
  byId: new Map(),
  /** @type {any[]} */
  cameras: [],
  /** @type {number | null} */
  selected: null,
  /** @type {{camera: import("./camera.js").ViewCamera, key: string} | null} The picture on screen. */
  shown: null,
  /** @type {IdsBuffer | null} The latest ids picture. */
  ids: null,
  /** @type {{centre: import("./camera.js").Vec3, answer: any, shape: import("./overlay.js").QueryShape | null} | null} */
  query: null,
  /** @type {number[]} When pictures were painted (performance.now()), the last few seconds. */
  paints: [],
  ready: false,
};

/** The view as it is now. @returns {import("./frames.js").View} */
function currentView() {
  const camera = state.orbit.camera(state.width, state.height);
  const mode = modeSelect.value;
  const shadows = shadowsBox.checked;
  const key = `${camera.key()}|${mode}|${shadows}|${state.revision}`;
  return { key, camera, mode, shadows, revision: state.revision };
}

/** Meters per unit of depth pictures: fine enough near, deep enough for the scene. */
function depthScale() {
  return Math.max(0.0002, (state.orbit.distance * 8) / 65535);
}

/** Asks for a picture of the current view. */
function requestFrame() {
  loop.show(currentView());
}

/** Redraws the overlay over the picture on screen. */
function redrawOverlay() {
  overlay.draw({
    camera: state.shown?.camera ?? null,
    viewKey: state.shown?.key ?? null,
    ids: state.ids,
    selected: state.selected,
    query: state.query?.shape ?? null,
  });
}

/** Sets both canvases to `width` × `height` (setting a size clears a canvas, so only on change). */
function sizeCanvases(width, height) {
  for (const c of [pictureCanvas, overlayCanvas]) {
    if (c.width !== width || c.height !== height) {
      c.width = width;
      c.height = height;
    }
  }
}

const loop = new FrameLoop({
  draw: (v) => fetchPicture(v.camera, v.mode, { shadows: v.shadows, depthScale: depthScale() }),
  paint: (picture, v) => {
    sizeCanvases(picture.width, picture.height);
    paint(pictureCtx, picture);
    state.shown = { camera: v.camera, key: v.key };
    if (picture.mode === "ids") {
      state.ids = new IdsBuffer(v.key, picture);
    }
    const now = performance.now();
    state.paints.push(now);
    while (state.paints.length && state.paints[0] < now - 2000) {
      state.paints.shift();
    }
    redrawOverlay();
    status.clearError();
  },
  failed: (error) => status.error(error, "Drawing the picture"),
  idle: async (v) => {
    if (state.ids?.viewKey === v.key) {
      return;
    }
    const picture = await fetchPicture(v.camera, "ids");
    state.ids = new IdsBuffer(v.key, picture);
    redrawOverlay();
  },
});

/** The ids picture of the picture on screen, fetched now if the idle one is not there yet. */
async function idsOnScreen() {
  const shown = state.shown;
  if (!shown) {
    return null;
  }
  if (state.ids?.viewKey === shown.key) {
    return state.ids;
  }
  const picture = await fetchPicture(shown.camera, "ids");
  const ids = new IdsBuffer(shown.key, picture);
  if (state.shown?.key === shown.key) {
    state.ids = ids;
  }
  return ids;
}

/** Fits the picture to the view (or to `?size=`) and redraws when the size changed. */
function fitPicture() {
  const size = state.fixedSize ?? {
    width: Math.max(16, Math.min(MAX_SIDE, Math.floor(view.clientWidth))),
    height: Math.max(16, Math.min(MAX_SIDE, Math.floor(view.clientHeight))),
  };
  if (size.width !== state.width || size.height !== state.height) {
    state.width = size.width;
    state.height = size.height;
    if (state.ready) {
      requestFrame();
    }
  }
}

/** The middle of the scene: the centre of the bodies' world positions' box, grown by their sizes. */
function sceneCentre() {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (const b of state.bodies) {
    const p = b.world_pose.position;
    let r = 0;
    if (b.bounds) {
      r = Math.max(...b.bounds.min.map(Math.abs), ...b.bounds.max.map(Math.abs));
    }
    for (let i = 0; i < 3; i++) {
      lo[i] = Math.min(lo[i], p[i] - r);
      hi[i] = Math.max(hi[i], p[i] + r);
    }
  }
  if (!Number.isFinite(lo[0])) {
    return /** @type {import("./camera.js").Vec3} */ ([0, 0, 0]);
  }
  return /** @type {import("./camera.js").Vec3} */ (lo.map((l, i) => (l + hi[i]) / 2));
}

/** Reads the bodies and redraws the parts tree. */
async function loadBodies() {
  const answer = await getJson("/v1/bodies");
  state.bodies = answer.bodies;
  state.byId = new Map(state.bodies.map((b) => [b.id, b]));
  renderParts($("parts"), state.bodies, state.selected, select);
}

/** Reads the stored cameras. */
async function loadCameras() {
  const answer = await getJson("/v1/cameras");
  state.cameras = answer.cameras;
  renderCameras($("cameras"), state.cameras, lookThrough);
}

/** Reads the stored lights. */
async function loadLights() {
  const answer = await getJson("/v1/lights");
  renderLights($("lights"), answer.lights);
}

/** Shows the selected body's properties (or none). */
async function showProperties() {
  const id = state.selected;
  const dl = $("properties");
  if (id === null) {
    renderProperties(dl, null, state.byId);
    return;
  }
  try {
    const body = await getJson(`/v1/bodies/${id}`);
    if (state.selected === id) {
      renderProperties(dl, body, state.byId);
    }
  } catch (e) {
    if (state.selected === id) {
      renderProperties(dl, null, state.byId);
    }
    status.error(e, `Reading body #${id}`);
  }
}

/**
 * Selects a body (null for none): its properties, its place in the parts tree and its
 * highlight in the picture.
 * @param {number | null} id
 */
function select(id) {
  state.selected = id;
  renderParts($("parts"), state.bodies, state.selected, select);
  redrawOverlay();
  void showProperties();
}

/** Looks through a stored camera. @param {any} camera */
function lookThrough(camera) {
  state.orbit.lookThrough(camera, sceneCentre());
  status.info(`Looking through camera ${camera.name}`);
  requestFrame();
}

/** Runs the spatial query about the chosen centre with the radius in the field. */
async function runQuery() {
  const query = state.query;
  if (!query) {
    return;
  }
  const radius = Number(radiusInput.value);
  if (!(Number.isFinite(radius) && radius >= 0)) {
    status.error(
      new Error(`the radius ${JSON.stringify(radiusInput.value)} is not a number of meters ≥ 0`),
      "Spatial query",
    );
    return;
  }
  try {
    const answer = await sphereQuery(query.centre, radius);
    if (state.query !== query) {
      return;
    }
    query.answer = answer;
    query.shape = shapeOf(answer);
    renderQuery($("query-results"), answer, select);
    const edges = query.shape.edges.length;
    $("query-centre").textContent =
      `Centre ${vec(query.centre)} (from the depth picture), radius ${num(radius)} m: ` +
      `${answer.bodies.length} bodies, ${edges} clipped edges, revision ${answer.revision}.`;
    redrawOverlay();
  } catch (e) {
    status.error(e, "Spatial query");
  }
}

/** Clears the spatial query. */
function clearQuery() {
  state.query = null;
  renderQuery($("query-results"), null, select);
  $("query-centre").textContent = "";
  redrawOverlay();
}

/** Picks the body under pixel (u, v) of the picture on screen. */
async function pick(u, v) {
  try {
    const ids = await idsOnScreen();
    if (!ids) {
      return;
    }
    select(ids.bodyAt(u, v));
  } catch (e) {
    status.error(e, "Picking");
  }
}

/** Takes the surface point under pixel (u, v) as the spatial query's centre. */
async function pickPoint(u, v) {
  const shown = state.shown;
  if (!shown) {
    return;
  }
  try {
    const centre = await pointUnder(shown.camera, u, v, depthScale());
    if (!centre) {
      status.info("No surface under that pixel: shift-click a body for the query's centre.");
      return;
    }
    state.query = { centre, answer: null, shape: null };
    await runQuery();
  } catch (e) {
    status.error(e, "Reading the point under the pointer");
  }
}

/** Bodies, cameras or lights changed: reread them, at most once per burst of changes. */
const reload = (() => {
  let timer = 0;
  let kinds = new Set();
  return (/** @type {string} */ kind) => {
    kinds.add(kind);
    clearTimeout(timer);
    timer = window.setTimeout(async () => {
      const now = kinds;
      kinds = new Set();
      try {
        const work = [];
        if (now.has("body")) {
          work.push(loadBodies(), showProperties());
          if (state.query) {
            work.push(runQuery());
          }
        }
        if (now.has("camera")) {
          work.push(loadCameras());
        }
        if (now.has("light")) {
          work.push(loadLights());
        }
        await Promise.all(work);
      } catch (e) {
        status.error(e, "Reading the world after a change");
      }
    }, 30);
  };
})();

const events = new WorldEvents({
  change: (change) => {
    state.revision = Math.max(state.revision, change.revision);
    for (const c of change.changes) {
      reload(c.kind);
      if (c.kind === "body" && c.action === "removed" && c.id === state.selected) {
        state.selected = null;
      }
    }
    requestFrame();
  },
  resync: (detail) => {
    status.info(`The change history no longer reaches back (${detail}); reading the world again.`);
    void connect(false);
  },
  state: (s, error) => {
    if (s === "error") {
      status.streamState("changes: disconnected", true);
      status.error(error, "Following changes");
    } else {
      status.streamState(s === "open" ? "changes: live" : `changes: ${s}`);
    }
  },
});

/**
 * Reads the world and starts following it.
 * @param {boolean} firstTime Also place the camera (through the first stored camera).
 */
async function connect(firstTime) {
  events.stop();
  try {
    const world = await getJson("/v1/world");
    state.revision = world.revision;
    await Promise.all([loadBodies(), loadCameras(), loadLights()]);
    if (firstTime || !state.home) {
      if (state.cameras.length) {
        state.orbit.lookThrough(state.cameras[0], sceneCentre());
      } else {
        state.orbit.target = sceneCentre();
      }
      state.home = state.orbit.clone();
    }
    events.start(world.revision);
    status.info(
      `Revision ${world.revision}: ${world.bodies} bodies, ${world.cameras} cameras, ${world.lights} lights.`,
    );
    state.ready = true;
    await showProperties();
    loop.invalidate();
    requestFrame();
  } catch (e) {
    status.error(e, "Reading the world");
  }
}

/** Shows the frame rate and latency. */
function showStats() {
  const now = performance.now();
  const recent = state.paints.filter((t) => t >= now - 1000).length;
  const s = loop.stats(50);
  const p50 = Number.isFinite(s.p50) ? `${Math.round(s.p50)} ms` : "–";
  status.stats(`${recent} fps · ${p50} per picture · ${state.width}×${state.height} · revision ${state.revision}`);
}

/** Hooks for tests and benchmarks: read the viewer's state, move its camera. */
const hooks = {
  /** Pictures painted so far. */
  get frames() {
    return loop.frames;
  },
  /** Whether the world has been read. */
  get ready() {
    return state.ready;
  },
  /** The selected body's id. */
  get selected() {
    return state.selected;
  },
  /** The newest revision known. */
  get revision() {
    return state.revision;
  },
  /** The camera of the picture on screen, as `POST /v1/appearance` takes it. */
  camera: () => state.shown?.camera.toRequest() ?? null,
  /** The camera of the current view (the newest asked for), in the same form. */
  viewCamera: () => state.orbit.camera(state.width, state.height).toRequest(),
  /** The body at pixel (u, v) of the latest ids picture for the picture on screen. */
  idsAt: (/** @type {number} */ u, /** @type {number} */ v) =>
    state.ids && state.ids.viewKey === state.shown?.key ? state.ids.bodyAt(u, v) : undefined,
  /** Picture statistics over the last `n` pictures. */
  stats: (/** @type {number} */ n) => loop.stats(n),
  /** Errors shown in the status line so far. */
  get errors() {
    return status.errors;
  },
  /**
   * Orbits by `step` degrees every animation frame (or, with `asap`, as often as timers
   * run, faster than pictures can come) for `ms` milliseconds, then answers the pictures
   * painted meanwhile, per second, with their latency percentiles.
   * @param {number} ms
   * @param {number} step
   * @param {boolean} asap
   */
  spin: (ms = 10000, step = 1, asap = false) =>
    new Promise((resolve) => {
      const frames0 = loop.frames;
      const failures0 = loop.failures;
      const started = performance.now();
      let ticks = 0;
      const tick = (/** @type {number} */ now) => {
        const elapsed = now - started;
        if (elapsed >= ms) {
          const frames = loop.frames - frames0;
          const seconds = elapsed / 1000;
          const { p50, p95 } = loop.stats(frames);
          const failures = loop.failures - failures0;
          resolve({
            frames,
            ticks,
            seconds,
            fps: frames / seconds,
            p50,
            p95,
            failures,
            width: state.width,
            height: state.height,
          });
          return;
        }
        ticks += 1;
        state.orbit.rotate(step, 0);
        requestFrame();
        next();
      };
      const next = asap ? () => setTimeout(() => tick(performance.now()), 0) : () => requestAnimationFrame(tick);
      next();
    }),
};

/** Wires the page up and reads the world. */
function start() {
  const size = new URLSearchParams(location.search).get("size")?.match(/^(\d{1,5})x(\d{1,5})$/);
  if (size) {
    state.fixedSize = {
      width: Math.max(16, Math.min(MAX_SIDE, Number(size[1]))),
      height: Math.max(16, Math.min(MAX_SIDE, Number(size[2]))),
    };
  }
  fitPicture();
  new ResizeObserver(fitPicture).observe(view);
  attachControls(overlayCanvas, state.orbit, { changed: requestFrame, pick, pickPoint });
  modeSelect.addEventListener("change", requestFrame);
  shadowsBox.addEventListener("change", requestFrame);
  $("reset-view").addEventListener("click", () => {
    if (state.home) {
      Object.assign(state.orbit, state.home.clone());
      requestFrame();
    }
  });
  tokenInput.placeholder = getToken() ? "set (hidden)" : "none";
  $("token-form").addEventListener("submit", (e) => {
    e.preventDefault();
    setToken(tokenInput.value);
    tokenInput.value = "";
    tokenInput.placeholder = getToken() ? "set (hidden)" : "none";
    void connect(!state.ready);
  });
  $("token-forget").addEventListener("click", () => {
    setToken("");
    tokenInput.placeholder = "none";
    void connect(!state.ready);
  });
  $("query-form").addEventListener("submit", (e) => {
    e.preventDefault();
    void runQuery();
  });
  $("query-clear").addEventListener("click", clearQuery);
  renderProperties($("properties"), null, state.byId);
  window.setInterval(showStats, 500);
  Object.defineProperty(window, "wingedViewer", { value: hooks });
  void connect(true);
}

start();
