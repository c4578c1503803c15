// The side panels: the selected body's properties, the parts tree, the stored cameras
// and lights, and the spatial query's results. Everything from the server is written as
// text (never as markup).

/**
 * An element with a class and text.
 * @param {string} tag
 * @param {string} [text]
 * @param {string} [className]
 * @returns {HTMLElement}
 */
function el(tag, text, className) {
  const e = document.createElement(tag);
  if (text !== undefined) {
    e.textContent = text;
  }
  if (className) {
    e.className = className;
  }
  return e;
}

/** A number with at most `digits` decimals. @param {number} x @param {number} [digits] */
export function num(x, digits = 4) {
  return Number.isFinite(x) ? String(Number(x.toFixed(digits))) : String(x);
}

/** A vector as "(x, y, z)". @param {number[]} v */
export function vec(v) {
  return `(${v.map((x) => num(x)).join(", ")})`;
}

/** A body's label: its name and id. @param {{id: number, name: string | null}} b */
export function label(b) {
  return b.name ? `${b.name} #${b.id}` : `#${b.id}`;
}

/**
 * Fills `dl` with the body's properties (`GET /v1/bodies/{id}`), or a hint when none is
 * selected.
 * @param {HTMLElement} dl
 * @param {any | null} body
 * @param {Map<number, any>} byId Bodies by id, to name the parent.
 */
export function renderProperties(dl, body, byId) {
  dl.replaceChildren();
  if (!body) {
    dl.append(el("dd", "Click a body in the picture or in the parts list.", "hint"));
    return;
  }
  const parent =
    body.parent === 1 ? "the world (#1)" : byId.has(body.parent) ? label(byId.get(body.parent)) : `#${body.parent}`;
  const e = body.euler;
  const rows = [
    ["id", String(body.id)],
    ["name", body.name ?? "(none)"],
    ["parent", parent],
    [
      "parts",
      body.parts.length ? body.parts.map((p) => (byId.has(p) ? label(byId.get(p)) : `#${p}`)).join(", ") : "none",
    ],
    ["position", vec(body.pose.position)],
    ["rotation", `${vec(body.pose.rotation)} (quaternion)`],
    ["world position", vec(body.world_pose.position)],
    ["counts", `${e.F} faces, ${e.E} edges, ${e.V} vertices${e.H ? `, ${e.H} handles` : ""}`],
    ["volume", `${num(body.volume, 6)} m³`],
    ["area", `${num(body.area, 6)} m²`],
    ["colour", String(body.color)],
  ];
  if (body.provisional) {
    rows.push(["provisional", `carved by ${body.views ?? "?"} views`]);
  }
  for (const [k, v] of rows) {
    const dd = el("dd", v);
    dd.dataset.field = k;
    if (k === "colour" && /^#[0-9a-fA-F]{6}$/.test(v)) {
      const swatch = el("span", "", "swatch");
      swatch.style.backgroundColor = v;
      dd.prepend(swatch);
    }
    dl.append(el("dt", k), dd);
  }
}

/**
 * Fills `list` with the parts tree: each body under its parent, top-level bodies first.
 * @param {HTMLElement} list
 * @param {any[]} bodies `GET /v1/bodies`' bodies.
 * @param {number | null} selected
 * @param {(id: number) => void} select
 */
export function renderParts(list, bodies, selected, select) {
  /** @type {Map<number, any[]>} */
  const children = new Map();
  const ids = new Set(bodies.map((b) => b.id));
  const tops = [];
  for (const b of bodies) {
    if (ids.has(b.parent) && b.parent !== b.id) {
      if (!children.has(b.parent)) {
        children.set(b.parent, []);
      }
      children.get(b.parent)?.push(b);
    } else {
      tops.push(b);
    }
  }
  const byId = (a, b) => a.id - b.id;
  /** @param {any[]} level @param {Set<number>} seen @returns {HTMLElement} */
  const branch = (level, seen) => {
    const ul = el("ul");
    for (const b of [...level].sort(byId)) {
      if (seen.has(b.id)) {
        continue;
      }
      seen.add(b.id);
      const li = el("li");
      const button = el("button", label(b), b.id === selected ? "body selected" : "body");
      button.type = "button";
      button.dataset.id = String(b.id);
      button.addEventListener("click", () => select(b.id));
      li.append(button);
      const kids = children.get(b.id);
      if (kids?.length) {
        li.append(branch(kids, seen));
      }
      ul.append(li);
    }
    return ul;
  };
  list.replaceChildren(...branch(tops, new Set()).childNodes);
  if (!bodies.length) {
    list.append(el("li", "The world has no bodies.", "hint"));
  }
}

/**
 * Fills `list` with the stored cameras, each with a button to look through it.
 * @param {HTMLElement} list
 * @param {any[]} cameras
 * @param {(camera: any) => void} look
 */
export function renderCameras(list, cameras, look) {
  list.replaceChildren();
  for (const c of cameras) {
    const li = el("li");
    const k = c.intrinsics;
    li.append(el("strong", c.name), el("span", ` at ${vec(c.pose.position)}, ${k.width}×${k.height} `, "detail"));
    const button = el("button", "Look through");
    button.type = "button";
    button.dataset.camera = c.name;
    button.addEventListener("click", () => look(c));
    li.append(button);
    list.append(li);
  }
  if (!cameras.length) {
    list.append(el("li", "No stored cameras.", "hint"));
  }
}

/**
 * Fills `list` with the stored lights.
 * @param {HTMLElement} list
 * @param {any[]} lights
 */
export function renderLights(list, lights) {
  list.replaceChildren();
  for (const l of lights) {
    const where = l.type === "sun" ? `sun along ${vec(l.direction)}` : `lamp at ${vec(l.position)}`;
    const li = el("li");
    li.append(el("strong", l.name), el("span", ` ${where}, intensity ${num(l.intensity)}`, "detail"));
    list.append(li);
  }
  if (!lights.length) {
    list.append(el("li", "No stored lights.", "hint"));
  }
}

/**
 * Fills `list` with a sphere query's bodies: name, distance and what of each is inside.
 * @param {HTMLElement} list
 * @param {any | null} answer
 * @param {(id: number) => void} select
 */
export function renderQuery(list, answer, select) {
  list.replaceChildren();
  if (!answer) {
    return;
  }
  for (const b of answer.bodies) {
    const li = el("li");
    const button = el("button", label(b), "body");
    button.type = "button";
    button.dataset.id = String(b.id);
    button.addEventListener("click", () => select(b.id));
    const faces = b.faces?.length ?? 0;
    const edges = b.edges?.length ?? 0;
    const verts = b.vertices?.length ?? 0;
    const where = b.inside ? "centre inside" : `${num(b.distance ?? 0)} m away`;
    li.append(button, el("span", ` ${where}; ${faces} faces, ${edges} edges, ${verts} vertices`, "detail"));
    list.append(li);
  }
  if (!answer.bodies.length) {
    list.append(el("li", "No body reaches into the sphere.", "hint"));
  }
}
