"""Draw the recognition benchmark's truth with Mesa's llvmpipe (moderngl), not winged.

For every `DIR/scene_NNN.json` written by `recognition_bench scenes`, draws the truth's
triangles through the exact camera with this script's own lighting (two suns and an
ambient term, gamma 2.2, 4x multisampling), then changes the gain (x0.8-1.2), blurs
(Gaussian, sigma 0.7 px) and adds noise (sigma 8/255): `image_NNN.png`. The depth along
the optical axis with noise growing with distance (sigma = 1.5 mm x d^2), in millimetres:
`depth_NNN.png` (16-bit, 0 = nothing). And the truth the report needs:
`truth_NNN.json` with, per body, its visible pixels and its whole projected pixels (drawn
alone on a canvas three times wider and taller), and the distractors' visible mask
(run-length coded).

    LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe python render.py DIR
"""

import json
import sys
from pathlib import Path

import cv2
import moderngl
import numpy as np

VERTEX = """
#version 330
uniform mat4 view;
uniform mat4 proj;
in vec3 pos;
in vec3 normal;
in vec3 color;
in float label;
out vec3 v_normal;
out vec3 v_color;
out float v_depth;
flat out int v_label;
void main() {
    v_normal = normal;
    v_color = color;
    vec4 eye = view * vec4(pos, 1.0);
    v_depth = -eye.z;
    v_label = int(label);
    gl_Position = proj * eye;
}
"""

SHADE = """
#version 330
in vec3 v_normal;
in vec3 v_color;
in float v_depth;
flat in int v_label;
out vec4 frag;
void main() {
    vec3 albedo = pow(v_color, vec3(2.2));
    vec3 a = normalize(vec3(-0.5, 0.35, -1.0));
    vec3 b = normalize(vec3(0.6, -0.2, -0.5));
    float light = 0.3 + 0.55 * max(dot(v_normal, -a), 0.0) + 0.25 * max(dot(v_normal, -b), 0.0);
    frag = vec4(pow(clamp(albedo * light, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
"""

DEPTH = """
#version 330
in vec3 v_normal;
in vec3 v_color;
in float v_depth;
flat in int v_label;
out vec2 frag;
void main() {
    frag = vec2(v_depth, float(v_label));
}
"""


def matrices(camera, width, height, near=0.05, far=50.0, shift=(0.0, 0.0)):
    k = camera["intrinsics"]
    r = np.array(camera["opencv"]["r"]).reshape(3, 3)
    t = np.array(camera["opencv"]["t"])
    flip = np.diag([1.0, -1.0, -1.0])
    view = np.eye(4)
    view[:3, :3] = flip @ r
    view[:3, 3] = flip @ t
    fx, fy = k["fx"], k["fy"]
    cx, cy = k["cx"] + shift[0], k["cy"] + shift[1]
    proj = np.zeros((4, 4))
    proj[0, 0] = 2 * fx / width
    proj[0, 2] = 1 - 2 * cx / width
    proj[1, 1] = 2 * fy / height
    proj[1, 2] = -(1 - 2 * cy / height)
    proj[2, 2] = -(far + near) / (far - near)
    proj[2, 3] = -2 * far * near / (far - near)
    proj[3, 2] = -1
    return view.T.astype("f4").tobytes(), proj.T.astype("f4").tobytes()


def vertices(bodies, only=None):
    rows = []
    for label, body in enumerate(bodies, start=1):
        if only is not None and label != only:
            continue
        tris = np.array(body["triangles"], dtype="f8").reshape(-1, 3, 3)
        if len(tris) == 0:
            continue
        n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        v = np.empty((len(tris), 3, 10), dtype="f4")
        v[:, :, 0:3] = tris
        v[:, :, 3:6] = n[:, None, :]
        v[:, :, 6:9] = (np.array(body["color"], dtype="f4") / 255.0)[None, None, :]
        v[:, :, 9] = label
        rows.append(v.reshape(-1, 10))
    return np.concatenate(rows) if rows else np.zeros((0, 10), dtype="f4")


class Drawer:
    def __init__(self):
        self.ctx = moderngl.create_standalone_context(backend="egl")
        self.ctx.gc_mode = "auto"
        self.shade = self.ctx.program(vertex_shader=VERTEX, fragment_shader=SHADE)
        self.depth = self.ctx.program(vertex_shader=VERTEX, fragment_shader=DEPTH)

    def _vao(self, prog, data):
        vbo = self.ctx.buffer(data.tobytes())
        # Attributes a program does not read are compiled out: skipped.
        return vbo, self.ctx.vertex_array(
            prog,
            [(vbo, "3f 3f 3f 1f", "pos", "normal", "color", "label")],
            skip_errors=True,
        )

    def colour(self, data, camera, w, h):
        fbo = self.ctx.framebuffer(
            color_attachments=[self.ctx.renderbuffer((w, h), 4, samples=4)],
            depth_attachment=self.ctx.depth_renderbuffer((w, h), samples=4),
        )
        out = self.ctx.simple_framebuffer((w, h), components=4)
        vbo, vao = self._vao(self.shade, data)
        view, proj = matrices(camera, w, h)
        self.shade["view"].write(view)
        self.shade["proj"].write(proj)
        fbo.use()
        self.ctx.enable(moderngl.DEPTH_TEST)
        fbo.clear(0.78, 0.80, 0.84, 1.0, depth=1.0)
        vao.render(moderngl.TRIANGLES)
        self.ctx.copy_framebuffer(out, fbo)
        pixels = np.frombuffer(out.read(components=3), dtype="u1").reshape(h, w, 3)[::-1]
        for x in (vao, vbo, fbo, out):
            x.release()
        return pixels.copy()

    def depth_labels(self, data, camera, w, h, shift=(0.0, 0.0)):
        colour = self.ctx.texture((w, h), 2, dtype="f4")
        fbo = self.ctx.framebuffer(
            color_attachments=[colour], depth_attachment=self.ctx.depth_renderbuffer((w, h))
        )
        vbo, vao = self._vao(self.depth, data)
        view, proj = matrices(camera, w, h, shift=shift)
        self.depth["view"].write(view)
        self.depth["proj"].write(proj)
        fbo.use()
        self.ctx.enable(moderngl.DEPTH_TEST)
        fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        vao.render(moderngl.TRIANGLES)
        raw = np.frombuffer(colour.read(), dtype="f4").reshape(h, w, 2)[::-1]
        for x in (vao, vbo, fbo, colour):
            x.release()
        return raw[:, :, 0].copy(), raw[:, :, 1].round().astype(int)


def runs(bits):
    flat = bits.ravel()
    out, current, n = [], False, 0
    for b in flat:
        b = bool(b)
        if b == current:
            n += 1
        else:
            out.append(n)
            current, n = b, 1
    out.append(n)
    return out


def main():
    folder = Path(sys.argv[1])
    drawer = Drawer()
    rng = np.random.default_rng(7)
    scenes = sorted(folder.glob("scene_*.json"))
    for n, path in enumerate(scenes):
        i = path.stem.split("_")[1]
        if (folder / f"truth_{i}.json").exists():
            continue
        if n % 25 == 0:
            print(f"scene {i}", flush=True)
        scene = json.loads(path.read_text())
        camera = scene["camera"]
        w, h = camera["intrinsics"]["width"], camera["intrinsics"]["height"]
        bodies = scene["triangles"]
        data = vertices(bodies)
        rgb = drawer.colour(data, camera, w, h).astype("f8")
        rgb *= rng.uniform(0.8, 1.2)
        rgb = cv2.GaussianBlur(rgb, (0, 0), 0.7)
        rgb += rng.normal(0.0, 8.0, rgb.shape)
        rgb = np.clip(np.round(rgb), 0, 255).astype("u1")
        cv2.imwrite(str(folder / f"image_{i}.png"), rgb[:, :, ::-1])
        depth, labels = drawer.depth_labels(data, camera, w, h)
        seen = depth > 0
        noisy = depth + rng.normal(0.0, 1.0, depth.shape) * 0.0015 * depth**2
        units = np.where(seen, np.clip(np.round(noisy * 1000.0), 1, 65535), 0).astype("u2")
        cv2.imwrite(str(folder / f"depth_{i}.png"), units)
        names = [b["name"] for b in bodies]
        visible = {n: int((labels == k).sum()) for k, n in enumerate(names, start=1)}
        whole = {}
        for k, n in enumerate(names, start=1):
            alone = vertices(bodies, only=k)
            d, _ = drawer.depth_labels(alone, camera, 3 * w, 3 * h, shift=(w, h))
            whole[n] = int((d > 0).sum())
        distractor = np.zeros((h, w), dtype=bool)
        for k, n in enumerate(names, start=1):
            if n.startswith("distractor"):
                distractor |= labels == k
        (folder / f"truth_{i}.json").write_text(
            json.dumps(
                {"visible_px": visible, "whole_px": whole, "distractor_runs": runs(distractor)}
            )
        )
    print(f"{len(scenes)} scenes drawn")


if __name__ == "__main__":
    main()
