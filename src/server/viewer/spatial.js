// The spatial query tool: a centre taken from the `depth` picture under a shift-click,
// and the sphere query `GET /v1/spatial/sphere` about it.

import { getJson } from "./api.js";
import { fetchPicture } from "./picture.js";

/**
 * The world point seen at pixel (u, v): the depth picture of the same camera gives its
 * distance along the view axis, and the pixel's ray (through the pixel's centre) gives
 * the direction. Null when no surface is there.
 * @param {import("./camera.js").ViewCamera} camera
 * @param {number} u
 * @param {number} v
 * @param {number} depthScale Meters per unit to ask for.
 * @returns {Promise<import("./camera.js").Vec3 | null>}
 */
export async function pointUnder(camera, u, v, depthScale) {
  const picture = await fetchPicture(camera, "depth", { depthScale });
  const { width, height } = picture;
  if (!(u >= 0 && v >= 0 && u < width && v < height)) {
    return null;
  }
  const values = /** @type {Uint16Array} */ (picture.values);
  const value = values[v * width + u];
  if (!value) {
    return null;
  }
  const depth = value * (picture.depthScale ?? depthScale);
  return camera.pointAt(u + 0.5, v + 0.5, depth);
}

/**
 * The sphere query's answer at `features` detail: the bodies in the ball, nearest
 * first, with their faces, clipped edges and vertices inside it.
 * @param {import("./camera.js").Vec3} centre
 * @param {number} radius
 * @returns {Promise<any>}
 */
export async function sphereQuery(centre, radius) {
  const q = new URLSearchParams({
    x: String(centre[0]),
    y: String(centre[1]),
    z: String(centre[2]),
    r: String(radius),
    detail: "features",
  });
  return getJson(`/v1/spatial/sphere?${q}`);
}

/**
 * The segments and vertices of a sphere answer, for the overlay.
 * @param {any} answer
 * @returns {import("./overlay.js").QueryShape}
 */
export function shapeOf(answer) {
  const edges = [];
  const vertices = [];
  for (const b of answer.bodies) {
    for (const e of b.edges ?? []) {
      edges.push([e.segment[0], e.segment[1]]);
    }
    for (const v of b.vertices ?? []) {
      vertices.push(v.position);
    }
  }
  return { centre: answer.center, radius: answer.radius, edges, vertices };
}
