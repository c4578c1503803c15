"""Draw the same triangles as winged's render benchmark with Mesa's llvmpipe (moderngl).

Reads the scenes `cargo run --release --example render_bench -- --dump DIR` writes, uploads
each scene's triangles once (flat normals, per-triangle colours), and for each of its
cameras draws them into a 1280x960 framebuffer with a z-buffer and Lambert shading of the
same suns (no shadows), then reads the pixels back (which waits for the drawing to finish).
Prints p50 / p99 per scene in milliseconds, in the same table layout as the Rust side.

    LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe python peer.py DIR
"""

import sys
import time
from pathlib import Path

import moderngl
import numpy as np

VERTEX = """
#version 330
uniform mat4 view;
uniform mat4 proj;
in vec3 pos;
in vec3 normal;
in vec3 color;
out vec3 v_normal;
out vec3 v_color;
void main() {
    v_normal = normal;
    v_color = color;
    gl_Position = proj * view * vec4(pos, 1.0);
}
"""

FRAGMENT = """
#version 330
uniform int suns;
uniform vec4 sun[4];   // xyz: direction the light travels; w: intensity
in vec3 v_normal;
in vec3 v_color;
out vec4 frag;
void main() {
    vec3 albedo = pow(v_color, vec3(2.2));
    float light = 0.25;
    for (int i = 0; i < suns; i++) {
        light += max(dot(v_normal, -sun[i].xyz), 0.0) * sun[i].w;
    }
    frag = vec4(pow(clamp(albedo * light, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
"""


def read_scene(path):
    data = path.read_bytes()
    at = 0

    def take(fmt, count=1):
        nonlocal at
        size = np.dtype(fmt).itemsize * count
        arr = np.frombuffer(data, dtype=np.dtype(fmt), count=count, offset=at)
        at += size
        return arr

    n_points, n_tris = take("<u4", 2)
    points = take("<f4", 3 * n_points).reshape(-1, 3)
    tris = take("<u4", 3 * n_tris).reshape(-1, 3)
    colors = take("u1", 3 * n_tris).reshape(-1, 3)
    (n_suns,) = take("<u4")
    suns = take("<f4", 4 * n_suns).reshape(-1, 4)
    (n_cams,) = take("<u4")
    cams = []
    for _ in range(n_cams):
        frame = take("<f8", 12).reshape(4, 3)
        fx, fy, cx, cy = take("<f8", 4)
        w, h = take("<u4", 2)
        cams.append((frame, fx, fy, cx, cy, int(w), int(h)))
    return points, tris, colors, suns, cams


def matrices(cam, near, far):
    frame, fx, fy, cx, cy, w, h = cam
    i, j, k, eye = frame
    rot = np.array([i, j, k])
    view = np.eye(4)
    view[:3, :3] = rot
    view[:3, 3] = -rot @ eye
    proj = np.zeros((4, 4))
    proj[0, 0] = 2 * fx / w
    proj[0, 2] = 1 - 2 * cx / w
    proj[1, 1] = 2 * fy / h
    proj[1, 2] = -(1 - 2 * cy / h)
    proj[2, 2] = -(far + near) / (far - near)
    proj[2, 3] = -2 * far * near / (far - near)
    proj[3, 2] = -1
    # moderngl takes column-major bytes.
    return view.T.astype("f4").tobytes(), proj.T.astype("f4").tobytes()


def percentile(samples, p):
    s = sorted(samples)
    return s[round((len(s) - 1) * p)]


def main():
    ctx = moderngl.create_standalone_context(backend="egl")
    print(f"{ctx.info['GL_RENDERER']}; p50 / p99 in ms (draw + read back)")
    print("| bodies | triangles | upload | z-buffer + Lambert, read back |")
    print("|---|---|---|---|")
    prog = ctx.program(vertex_shader=VERTEX, fragment_shader=FRAGMENT)
    for path in sorted(Path(sys.argv[1]).glob("blocks_*.bin"), key=lambda p: int(p.stem[7:])):
        points, tris, colors, suns, cams = read_scene(path)
        t0 = time.perf_counter()
        corners = points[tris]  # (n, 3, 3)
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
        vertices = np.empty((len(tris), 3, 9), dtype="f4")
        vertices[:, :, 0:3] = corners
        vertices[:, :, 3:6] = normals[:, None, :]
        vertices[:, :, 6:9] = (colors.astype("f4") / 255.0)[:, None, :]
        vbo = ctx.buffer(vertices.tobytes())
        vao = ctx.vertex_array(prog, [(vbo, "3f 3f 3f", "pos", "normal", "color")])
        w, h = cams[0][5], cams[0][6]
        fbo = ctx.simple_framebuffer((w, h), components=4)
        fbo.use()
        ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        ctx.finish()
        upload_ms = (time.perf_counter() - t0) * 1e3
        prog["suns"].value = min(len(suns), 4)
        sun = np.zeros((4, 4), dtype="f4")
        sun[: len(suns)] = suns[:4]
        prog["sun"].write(sun.tobytes())
        extent = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
        samples = []
        for n, cam in enumerate(cams[:2] + cams):
            view, proj = matrices(cam, 0.01, 4 * extent + 10)
            t = time.perf_counter()
            prog["view"].write(view)
            prog["proj"].write(proj)
            fbo.clear(200 / 255, 210 / 255, 225 / 255, 1.0, depth=1.0)
            vao.render(moderngl.TRIANGLES)
            pixels = fbo.read(components=3)
            elapsed = (time.perf_counter() - t) * 1e3
            if n >= 2:  # the first two are warm-up
                samples.append(elapsed)
            assert len(pixels) == w * h * 3
        print(
            f"| {path.stem[7:]} | {len(tris)} | {upload_ms:.1f} | "
            f"{percentile(samples, 0.5):.2f} / {percentile(samples, 0.99):.2f} |",
            flush=True,
        )
        vao.release()
        vbo.release()
        fbo.release()


if __name__ == "__main__":
    main()
