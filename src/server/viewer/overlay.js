// The overlay canvas over the picture: the selected body's highlight (from the ids
// picture of the view on screen) and the spatial query's sphere and clipped edges,
// projected in the browser with the camera the picture was drawn with.

/** Highlight fill and outline colours (RGBA). */
const FILL = [255, 170, 0, 110];
const OUTLINE = [255, 100, 0, 255];
/** The outline's width, pixels. */
const OUTLINE_WIDTH = 2;

/**
 * A spatial query to show.
 * @typedef {object} QueryShape
 * @property {import("./camera.js").Vec3} centre
 * @property {number} radius
 * @property {Array<[import("./camera.js").Vec3, import("./camera.js").Vec3]>} edges Clipped segments.
 * @property {import("./camera.js").Vec3[]} vertices Vertices inside the sphere.
 */

/** Draws the overlay and remembers the highlight so that it is built once per picture. */
export class Overlay {
  /** @param {HTMLCanvasElement} canvas */
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = /** @type {CanvasRenderingContext2D} */ (canvas.getContext("2d"));
    /** @type {{key: string, image: ImageData} | null} */
    this.highlight = null;
  }

  /**
   * The highlight of body `id` in `ids`, built or reused.
   * @param {import("./picking.js").IdsBuffer} ids
   * @param {number} id
   * @returns {ImageData | null}
   */
  highlightOf(ids, id) {
    const key = `${ids.viewKey}|${ids.revision}|${id}`;
    if (this.highlight?.key === key) {
      return this.highlight.image;
    }
    const mask = ids.maskOf(id);
    if (!mask) {
      this.highlight = null;
      return null;
    }
    const { width: w, height: h } = ids;
    const image = this.ctx.createImageData(w, h);
    const px = image.data;
    /** Whether (u, v) is covered; outside the picture counts as not. */
    const covered = (u, v) => u >= 0 && v >= 0 && u < w && v < h && mask[v * w + u] === 1;
    for (let v = 0; v < h; v++) {
      for (let u = 0; u < w; u++) {
        const i = v * w + u;
        if (!mask[i]) {
          continue;
        }
        let edge = false;
        for (let d = 1; d <= OUTLINE_WIDTH && !edge; d++) {
          edge = !covered(u - d, v) || !covered(u + d, v) || !covered(u, v - d) || !covered(u, v + d);
        }
        const c = edge ? OUTLINE : FILL;
        px[i * 4] = c[0];
        px[i * 4 + 1] = c[1];
        px[i * 4 + 2] = c[2];
        px[i * 4 + 3] = c[3];
      }
    }
    this.highlight = { key, image };
    return image;
  }

  /**
   * Redraws everything over the picture on screen.
   * @param {object} scene
   * @param {import("./camera.js").ViewCamera | null} scene.camera The camera of the picture on screen.
   * @param {string | null} scene.viewKey Its view key.
   * @param {import("./picking.js").IdsBuffer | null} scene.ids The latest ids picture.
   * @param {number | null} scene.selected The selected body.
   * @param {QueryShape | null} scene.query The spatial query.
   */
  draw({ camera, viewKey, ids, selected, query }) {
    const { ctx, canvas } = this;
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    if (
      selected !== null &&
      ids &&
      ids.viewKey === viewKey &&
      ids.width === canvas.width &&
      ids.height === canvas.height
    ) {
      const image = this.highlightOf(ids, selected);
      if (image) {
        ctx.putImageData(image, 0, 0);
      }
    }
    if (query && camera) {
      this.drawQuery(camera, query);
    }
  }

  /**
   * The query's centre, its sphere's outline as seen at the centre's depth, and the
   * clipped edges and vertices inside it.
   * @param {import("./camera.js").ViewCamera} camera
   * @param {QueryShape} query
   */
  drawQuery(camera, query) {
    const { ctx } = this;
    ctx.save();
    ctx.lineWidth = 2.5;
    ctx.strokeStyle = "#00e0ff";
    ctx.beginPath();
    for (const [a, b] of query.edges) {
      const s = camera.projectSegment(a, b);
      if (s) {
        ctx.moveTo(s[0][0], s[0][1]);
        ctx.lineTo(s[1][0], s[1][1]);
      }
    }
    ctx.stroke();
    ctx.fillStyle = "#00e0ff";
    for (const p of query.vertices) {
      const q = camera.project(p);
      if (q) {
        ctx.fillRect(q[0] - 3, q[1] - 3, 6, 6);
      }
    }
    const c = camera.project(query.centre);
    if (c) {
      const depth = -camera.toCamera(query.centre)[2];
      const r = (query.radius * camera.intrinsics.fy) / depth;
      ctx.lineWidth = 1.5;
      ctx.strokeStyle = "#ff3df0";
      ctx.setLineDash([6, 4]);
      ctx.beginPath();
      ctx.arc(c[0], c[1], r, 0, 2 * Math.PI);
      ctx.stroke();
      ctx.setLineDash([]);
      ctx.beginPath();
      ctx.moveTo(c[0] - 6, c[1]);
      ctx.lineTo(c[0] + 6, c[1]);
      ctx.moveTo(c[0], c[1] - 6);
      ctx.lineTo(c[0], c[1] + 6);
      ctx.stroke();
    }
    ctx.restore();
  }
}
