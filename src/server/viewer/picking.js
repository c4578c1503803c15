// Picking: which body is under a pixel, read from an `ids` picture of the same view.
// In an ids PNG each pixel holds a value v (0 for the background); the `X-Body-Ids`
// legend names the body id of each v.

/** The ids picture of one view, and what can be asked of it. */
export class IdsBuffer {
  /**
   * @param {string} viewKey The key of the view it was drawn for.
   * @param {import("./picture.js").Picture} picture An `ids` picture.
   */
  constructor(viewKey, picture) {
    this.viewKey = viewKey;
    this.width = picture.width;
    this.height = picture.height;
    this.revision = picture.revision;
    this.values = /** @type {Uint16Array} */ (picture.values);
    this.legend = /** @type {Map<number, number>} */ (picture.legend);
    /** @type {Map<number, number>} body id → pixel value */
    this.valueOf = new Map([...this.legend].map(([v, id]) => [id, v]));
  }

  /**
   * The body id at pixel (u, v), or null for the background or outside the picture.
   * @param {number} u
   * @param {number} v
   * @returns {number | null}
   */
  bodyAt(u, v) {
    if (!(u >= 0 && v >= 0 && u < this.width && v < this.height)) {
      return null;
    }
    const value = this.values[Math.floor(v) * this.width + Math.floor(u)];
    return value ? (this.legend.get(value) ?? null) : null;
  }

  /**
   * The pixels covered by body `id` (1 where covered), or null when it is not in view.
   * @param {number} id
   * @returns {Uint8Array | null}
   */
  maskOf(id) {
    const value = this.valueOf.get(id);
    if (value === undefined) {
      return null;
    }
    const mask = new Uint8Array(this.values.length);
    for (let i = 0; i < mask.length; i++) {
      mask[i] = this.values[i] === value ? 1 : 0;
    }
    return mask;
  }

  /**
   * A pixel well inside body `id`'s region (the covered pixel nearest the region's
   * centroid), or null when it is not in view.
   * @param {number} id
   * @returns {[number, number] | null}
   */
  pixelOf(id) {
    const value = this.valueOf.get(id);
    if (value === undefined) {
      return null;
    }
    let n = 0;
    let su = 0;
    let sv = 0;
    for (let i = 0; i < this.values.length; i++) {
      if (this.values[i] === value) {
        n += 1;
        su += i % this.width;
        sv += Math.floor(i / this.width);
      }
    }
    if (!n) {
      return null;
    }
    const cu = su / n;
    const cv = sv / n;
    let best = null;
    let bestD = Infinity;
    for (let i = 0; i < this.values.length; i++) {
      if (this.values[i] === value) {
        const u = i % this.width;
        const v = Math.floor(i / this.width);
        const d = (u - cu) ** 2 + (v - cv) ** 2;
        if (d < bestD) {
          bestD = d;
          best = [u, v];
        }
      }
    }
    return best;
  }
}
