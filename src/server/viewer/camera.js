// The pinhole camera the viewer draws with, in the server's own conventions: Baumgart's
// frame (i right, j up, k toward the viewer; the camera looks along −k), pixels measured
// from the top-left corner of the top-left pixel, u right and v down. A camera made here
// projects exactly as the server's `look_at` camera of the same eye, target and up.

/** @typedef {[number, number, number]} Vec3 */

/** @param {Vec3} a @param {Vec3} b @returns {Vec3} */
export const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
/** @param {Vec3} a @param {Vec3} b @returns {Vec3} */
export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
/** @param {Vec3} a @param {number} s @returns {Vec3} */
export const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
/** @param {Vec3} a @param {Vec3} b @returns {number} */
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
/** @param {Vec3} a @param {Vec3} b @returns {Vec3} */
export const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
/** @param {Vec3} a @returns {number} */
export const length = (a) => Math.hypot(a[0], a[1], a[2]);
/** @param {Vec3} a @returns {Vec3} */
export const normalize = (a) => scale(a, 1 / (length(a) || 1));

/**
 * Pinhole intrinsics in pixels.
 * @typedef {{width: number, height: number, fx: number, fy: number, cx: number, cy: number}} Intrinsics
 */

/** A camera at `eye` looking at `target` with `up` up in the image, as the server's
 * `look_at` builds it: k = (eye − target)/|eye − target|, i = up × k normalised,
 * j = k × i. */
export class ViewCamera {
  /**
   * @param {Vec3} eye
   * @param {Vec3} target
   * @param {Intrinsics} intrinsics
   * @param {Vec3} [up]
   */
  constructor(eye, target, intrinsics, up = [0, 0, 1]) {
    this.eye = eye;
    this.target = target;
    this.up = up;
    this.intrinsics = intrinsics;
    this.k = normalize(sub(eye, target));
    this.i = normalize(cross(up, this.k));
    this.j = cross(this.k, this.i);
  }

  /** The camera as `POST /v1/appearance` takes it inline. */
  toRequest() {
    const k = this.intrinsics;
    return {
      look_at: { eye: this.eye, target: this.target, up: this.up },
      intrinsics: { width: k.width, height: k.height, fx: k.fx, fy: k.fy, cx: k.cx, cy: k.cy },
    };
  }

  /** A string that changes whenever the picture would. */
  key() {
    return JSON.stringify(this.toRequest());
  }

  /**
   * World point to camera coordinates (x along i, y along j, z along k; in front of the
   * camera z < 0).
   * @param {Vec3} p
   * @returns {Vec3}
   */
  toCamera(p) {
    const d = sub(p, this.eye);
    return [dot(d, this.i), dot(d, this.j), dot(d, this.k)];
  }

  /**
   * The pixel (u, v) a world point projects to, or null when it is not in front.
   * @param {Vec3} p
   * @returns {[number, number] | null}
   */
  project(p) {
    const c = this.toCamera(p);
    if (c[2] >= 0) {
      return null;
    }
    const d = -c[2];
    const k = this.intrinsics;
    return [k.cx + (k.fx * c[0]) / d, k.cy - (k.fy * c[1]) / d];
  }

  /**
   * The world point seen at pixel (u, v) at distance `depth` along the view axis (−z).
   * @param {number} u
   * @param {number} v
   * @param {number} depth meters
   * @returns {Vec3}
   */
  pointAt(u, v, depth) {
    const k = this.intrinsics;
    const x = ((u - k.cx) / k.fx) * depth;
    const y = (-(v - k.cy) / k.fy) * depth;
    return add(this.eye, add(add(scale(this.i, x), scale(this.j, y)), scale(this.k, -depth)));
  }

  /**
   * A segment clipped to lie in front of the near plane and projected, or null when it
   * is wholly behind it.
   * @param {Vec3} a
   * @param {Vec3} b
   * @param {number} [near]
   * @returns {[[number, number], [number, number]] | null}
   */
  projectSegment(a, b, near = 0.01) {
    let ca = this.toCamera(a);
    let cb = this.toCamera(b);
    const inFront = (c) => -c[2] >= near;
    if (!inFront(ca) && !inFront(cb)) {
      return null;
    }
    const clip = (p, q) => {
      const t = (-near - p[2]) / (q[2] - p[2]);
      return [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), -near];
    };
    if (!inFront(ca)) {
      ca = clip(ca, cb);
    } else if (!inFront(cb)) {
      cb = clip(cb, ca);
    }
    const k = this.intrinsics;
    const px = (c) => [k.cx + (k.fx * c[0]) / -c[2], k.cy - (k.fy * c[1]) / -c[2]];
    return [px(ca), px(cb)];
  }
}
