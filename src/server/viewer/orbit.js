// Orbit navigation: a camera circling a target point with z up. Drag to orbit,
// right-drag or shift-drag to pan, wheel to zoom; a click without movement picks.

import { ViewCamera, add, normalize, scale, dot, sub } from "./camera.js";

/** Degrees of turn per pixel dragged. */
const DEGREES_PER_PIXEL = 0.3;
/** How far from straight up or down the view may tilt, degrees. */
const MAX_ELEVATION = 89;
/** Pixels a pointer may move and still count as a click. */
const CLICK_SLOP = 4;

/** @typedef {import("./camera.js").Vec3} Vec3 */

/** Where an orbit camera is: a target, a distance, two angles and a field of view. */
export class Orbit {
  constructor() {
    /** @type {Vec3} */
    this.target = [0, 0, 0.5];
    this.distance = 3;
    /** Degrees, counter-clockwise from +x, of the eye seen from the target. */
    this.azimuth = -45;
    /** Degrees above the target's horizontal plane. */
    this.elevation = 30;
    /** Vertical field of view, degrees. */
    this.fovY = 45;
  }

  /** A copy. @returns {Orbit} */
  clone() {
    return Object.assign(new Orbit(), this, { target: [...this.target] });
  }

  /** The eye's position. @returns {Vec3} */
  eye() {
    const a = (this.azimuth * Math.PI) / 180;
    const e = (this.elevation * Math.PI) / 180;
    const dir = [Math.cos(e) * Math.cos(a), Math.cos(e) * Math.sin(a), Math.sin(e)];
    return add(this.target, scale(/** @type {Vec3} */ (dir), this.distance));
  }

  /**
   * The camera for a `width` × `height` picture.
   * @param {number} width
   * @param {number} height
   * @returns {ViewCamera}
   */
  camera(width, height) {
    const f = height / 2 / Math.tan((this.fovY * Math.PI) / 360);
    return new ViewCamera(this.eye(), this.target, {
      width,
      height,
      fx: f,
      fy: f,
      cx: width / 2,
      cy: height / 2,
    });
  }

  /** Turns about the target. @param {number} dAzimuth degrees @param {number} dElevation degrees */
  rotate(dAzimuth, dElevation) {
    this.azimuth = (((this.azimuth + dAzimuth) % 360) + 360) % 360;
    this.elevation = Math.max(-MAX_ELEVATION, Math.min(MAX_ELEVATION, this.elevation + dElevation));
  }

  /**
   * Moves the target (and the eye with it) by a drag of (dx, dy) pixels in a picture
   * `height` pixels high, so that the point under the pointer follows it.
   * @param {number} dx
   * @param {number} dy
   * @param {number} height
   */
  pan(dx, dy, height) {
    const cam = this.camera(height, height);
    const metersPerPixel = this.distance / cam.intrinsics.fy;
    const move = add(scale(cam.i, -dx * metersPerPixel), scale(cam.j, dy * metersPerPixel));
    this.target = add(this.target, move);
  }

  /** Moves toward the target by `factor` (below 1 nearer). @param {number} factor */
  zoom(factor) {
    this.distance = Math.max(0.05, Math.min(1e4, this.distance * factor));
  }

  /**
   * Takes the place of a stored camera: its eye, view direction and vertical field of
   * view. The target is put on the view axis, level with `centre` (the scene's middle).
   * @param {{pose: {position: Vec3}, view_direction: Vec3, intrinsics: {height: number, fy: number}}} stored
   * @param {Vec3} centre
   */
  lookThrough(stored, centre) {
    const eye = stored.pose.position;
    const dir = normalize(stored.view_direction);
    let d = dot(sub(centre, eye), dir);
    if (!(d > 0.1)) {
      d = 1;
    }
    this.target = add(eye, scale(dir, d));
    this.distance = d;
    this.azimuth = (Math.atan2(-dir[1], -dir[0]) * 180) / Math.PI;
    this.elevation = Math.max(
      -MAX_ELEVATION,
      Math.min(MAX_ELEVATION, (Math.asin(Math.max(-1, Math.min(1, -dir[2]))) * 180) / Math.PI),
    );
    const k = stored.intrinsics;
    this.fovY = (2 * Math.atan(k.height / 2 / k.fy) * 180) / Math.PI;
  }
}

/**
 * What the pointer controls report.
 * @typedef {object} ControlHandlers
 * @property {() => void} changed The orbit moved.
 * @property {(u: number, v: number) => void} pick A plain click at pixel (u, v).
 * @property {(u: number, v: number) => void} pickPoint A shift-click at pixel (u, v).
 */

/**
 * Connects mouse and wheel input on `element` to `orbit`.
 * @param {HTMLElement} element The surface over the picture (its CSS pixels are the picture's).
 * @param {Orbit} orbit
 * @param {ControlHandlers} on
 */
export function attachControls(element, orbit, on) {
  /** @type {{x: number, y: number, startX: number, startY: number, button: number, shift: boolean, moved: boolean, id: number} | null} */
  let drag = null;

  element.addEventListener("contextmenu", (e) => e.preventDefault());

  element.addEventListener("pointerdown", (e) => {
    if (drag || (e.button !== 0 && e.button !== 2)) {
      return;
    }
    drag = {
      x: e.clientX,
      y: e.clientY,
      startX: e.clientX,
      startY: e.clientY,
      button: e.button,
      shift: e.shiftKey,
      moved: false,
      id: e.pointerId,
    };
    element.setPointerCapture(e.pointerId);
    e.preventDefault();
  });

  element.addEventListener("pointermove", (e) => {
    if (!drag || e.pointerId !== drag.id) {
      return;
    }
    if (!drag.moved && Math.hypot(e.clientX - drag.startX, e.clientY - drag.startY) <= CLICK_SLOP) {
      return;
    }
    drag.moved = true;
    const dx = e.clientX - drag.x;
    const dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.button === 2 || drag.shift) {
      orbit.pan(dx, dy, element.clientHeight || 1);
    } else {
      orbit.rotate(-dx * DEGREES_PER_PIXEL, dy * DEGREES_PER_PIXEL);
    }
    on.changed();
  });

  const end = (/** @type {PointerEvent} */ e) => {
    if (!drag || e.pointerId !== drag.id) {
      return;
    }
    const d = drag;
    drag = null;
    if (element.hasPointerCapture(e.pointerId)) {
      element.releasePointerCapture(e.pointerId);
    }
    if (!d.moved && e.type === "pointerup" && d.button === 0) {
      const r = element.getBoundingClientRect();
      const u = Math.floor(e.clientX - r.left);
      const v = Math.floor(e.clientY - r.top);
      if (d.shift) {
        on.pickPoint(u, v);
      } else {
        on.pick(u, v);
      }
    }
  };
  element.addEventListener("pointerup", end);
  element.addEventListener("pointercancel", end);

  element.addEventListener(
    "wheel",
    (e) => {
      e.preventDefault();
      const lines = e.deltaMode === 1 ? 40 : e.deltaMode === 2 ? 400 : 1;
      orbit.zoom(Math.exp(e.deltaY * lines * 0.001));
      on.changed();
    },
    { passive: false },
  );
}
