// Pictures from `POST /v1/appearance`: asking for one, decoding it, painting it.
// `shaded`, `wire` and `hidden` come as 8-bit RGB PNGs the browser decodes; `depth` and
// `ids` as 16-bit grayscale PNGs decoded by png16.js and painted in false colour.

import { request } from "./api.js";
import { decodeGray16 } from "./png16.js";

/** The drawing modes the server offers. */
export const MODES = ["shaded", "wire", "hidden", "depth", "ids"];

/**
 * A decoded picture.
 * @typedef {object} Picture
 * @property {string} mode
 * @property {number} width
 * @property {number} height
 * @property {number} revision The world revision drawn (from the ETag).
 * @property {ImageBitmap} [bitmap] shaded, wire, hidden.
 * @property {Uint16Array} [values] depth and ids: one sample per pixel.
 * @property {Map<number, number>} [legend] ids: pixel value → body id.
 * @property {number} [depthScale] depth: meters per unit.
 */

/**
 * The revision an ETag names (`"12"` → 12), or NaN.
 * @param {string | null} tag
 */
function revisionOf(tag) {
  return tag ? Number(tag.replace(/^W\//, "").replaceAll('"', "")) : NaN;
}

/**
 * The `X-Body-Ids` legend: "1=5,2=7" → {1 → 5, 2 → 7}.
 * @param {string} text
 * @returns {Map<number, number>}
 */
export function parseLegend(text) {
  const legend = new Map();
  for (const pair of text.split(",")) {
    const [value, id] = pair.split("=").map((s) => Number(s.trim()));
    if (Number.isInteger(value) && Number.isFinite(id)) {
      legend.set(value, id);
    }
  }
  return legend;
}

/**
 * The legend of an ids picture too long for the header, from its JSON form.
 * @param {object} camera The camera as the request gave it.
 * @returns {Promise<Map<number, number>>}
 */
async function legendAsJson(camera) {
  const res = await request("POST", "/v1/appearance", { json: { camera, mode: "ids", format: "json" } });
  const answer = await res.json();
  return new Map(answer.bodies.map((b) => [b.value, b.id]));
}

/**
 * Asks the server for a picture and decodes it.
 * @param {import("./camera.js").ViewCamera} camera
 * @param {string} mode One of MODES.
 * @param {{shadows?: boolean, depthScale?: number}} [options]
 * @returns {Promise<Picture>}
 */
export async function fetchPicture(camera, mode, options = {}) {
  /** @type {Record<string, unknown>} */
  const body = { camera: camera.toRequest(), mode, format: "png" };
  if (mode === "shaded" && options.shadows !== undefined) {
    body.shadows = options.shadows;
  }
  if (mode === "depth" && options.depthScale) {
    body.depth_scale = options.depthScale;
  }
  const res = await request("POST", "/v1/appearance", { json: body, headers: { Accept: "image/png" } });
  const revision = revisionOf(res.headers.get("ETag"));
  const { width, height } = camera.intrinsics;
  const blob = await res.blob();
  if (mode === "depth" || mode === "ids") {
    const gray = await decodeGray16(await blob.arrayBuffer());
    /** @type {Picture} */
    const picture = { mode, width: gray.width, height: gray.height, revision, values: gray.data };
    if (mode === "depth") {
      picture.depthScale = Number(res.headers.get("X-Depth-Scale")) || options.depthScale || 0.001;
    } else {
      const header = res.headers.get("X-Body-Ids");
      picture.legend = header !== null ? parseLegend(header) : await legendAsJson(body.camera);
    }
    return picture;
  }
  const bitmap = await createImageBitmap(blob);
  return { mode, width: bitmap.width || width, height: bitmap.height || height, revision, bitmap };
}

/**
 * A colour for a body id, the same every time: its hue spread by the golden ratio.
 * @param {number} id
 * @returns {[number, number, number]}
 */
export function colourOf(id) {
  const hue = (id * 0.618033988749895) % 1;
  const s = 0.65;
  const l = 0.55;
  const f = (n) => {
    const k = (n + hue * 12) % 12;
    const a = s * Math.min(l, 1 - l);
    return Math.round(255 * (l - a * Math.max(-1, Math.min(k - 3, 9 - k, 1))));
  };
  return [f(0), f(8), f(4)];
}

/** The colour of the background in an ids picture. */
const BACKGROUND = [24, 24, 32];
/** The colour of a pixel value the legend does not name. */
const UNKNOWN = [255, 255, 255];

/**
 * Paints a picture on a canvas of its size.
 * @param {CanvasRenderingContext2D} ctx
 * @param {Picture} picture
 */
export function paint(ctx, picture) {
  if (picture.bitmap) {
    ctx.drawImage(picture.bitmap, 0, 0);
    picture.bitmap.close();
    return;
  }
  const { width, height } = picture;
  const values = /** @type {Uint16Array} */ (picture.values);
  const image = ctx.createImageData(width, height);
  const px = image.data;
  if (picture.mode === "depth") {
    let lo = Infinity;
    let hi = 0;
    for (const v of values) {
      if (v) {
        lo = Math.min(lo, v);
        hi = Math.max(hi, v);
      }
    }
    const span = Math.max(1, hi - lo);
    for (let i = 0; i < values.length; i++) {
      const v = values[i];
      // Near surfaces light, far ones dark, the background black.
      const g = v ? Math.round(235 - (200 * (v - lo)) / span) : 0;
      const j = i * 4;
      px[j] = g;
      px[j + 1] = g;
      px[j + 2] = g;
      px[j + 3] = 255;
    }
  } else {
    const legend = picture.legend ?? new Map();
    /** @type {Map<number, [number, number, number]>} */
    const colours = new Map();
    for (const [value, id] of legend) {
      colours.set(value, colourOf(id));
    }
    for (let i = 0; i < values.length; i++) {
      const c = values[i] ? (colours.get(values[i]) ?? UNKNOWN) : BACKGROUND;
      const j = i * 4;
      px[j] = c[0];
      px[j + 1] = c[1];
      px[j + 2] = c[2];
      px[j + 3] = 255;
    }
  }
  ctx.putImageData(image, 0, 0);
}
