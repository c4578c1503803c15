// The picture loop: at most one picture request in flight, the newest view winning.
// While a request is out, later views only replace the one waiting; when it returns,
// the waiting view (if any, and if it differs from the one just drawn) is sent next.
// Once a view has stayed put for a moment, an optional idle task runs for it (the
// viewer fetches the `ids` picture for picking then), still one request at a time.

/** How long a view must stay unchanged before the idle task runs, ms. */
const SETTLE_MS = 120;
/** Latencies kept for the statistics. */
const KEPT = 2000;

/**
 * A view to draw: everything the picture depends on, and a key that differs whenever
 * the picture would.
 * @typedef {{key: string, camera: import("./camera.js").ViewCamera, mode: string, shadows: boolean, revision: number}} View
 */

/**
 * @template Frame
 * @typedef {object} LoopHandlers
 * @property {(view: View) => Promise<Frame>} draw Fetches and decodes the picture of a view.
 * @property {(frame: Frame, view: View, ms: number) => void} paint Shows it.
 * @property {(error: unknown, view: View) => void} failed Reports a picture that could not be had.
 * @property {(view: View) => Promise<void>} [idle] Work for a view that has settled.
 */

/** @template Frame */
export class FrameLoop {
  /** @param {LoopHandlers<Frame>} handlers */
  constructor(handlers) {
    this.handlers = handlers;
    /** A request (picture or idle task) is out. */
    this.busy = false;
    /** @type {View | null} The newest view not yet sent. */
    this.pending = null;
    /** @type {View | null} The newest view asked for. */
    this.latest = null;
    /** @type {string | null} The key of the picture on screen. */
    this.shownKey = null;
    /** Pictures painted. */
    this.frames = 0;
    /** Pictures refused or failed. */
    this.failures = 0;
    /** @type {number[]} Request-to-paint times of the latest pictures, ms. */
    this.latencies = [];
    this.idleTimer = 0;
  }

  /** Asks for a picture of `view`; the newest view asked for wins. @param {View} view */
  show(view) {
    this.pending = view;
    this.latest = view;
    clearTimeout(this.idleTimer);
    void this.pump();
  }

  /** Forgets which picture is on screen, so that the next view is drawn even if unchanged. */
  invalidate() {
    this.shownKey = null;
  }

  /** Sends the waiting view, unless a request is out or it is already on screen. */
  async pump() {
    if (this.busy || !this.pending) {
      return;
    }
    const view = this.pending;
    this.pending = null;
    if (view.key === this.shownKey) {
      this.settle(view);
      return;
    }
    this.busy = true;
    let drawn = false;
    const started = performance.now();
    try {
      const frame = await this.handlers.draw(view);
      this.handlers.paint(frame, view, performance.now() - started);
      this.shownKey = view.key;
      this.frames += 1;
      drawn = true;
      this.latencies.push(performance.now() - started);
      if (this.latencies.length > KEPT) {
        this.latencies.splice(0, this.latencies.length - KEPT);
      }
    } catch (e) {
      this.failures += 1;
      this.handlers.failed(e, view);
    } finally {
      this.busy = false;
    }
    if (this.pending) {
      void this.pump();
    } else if (drawn) {
      this.settle(view);
    }
  }

  /** Runs the idle task for `view` once it has stayed the latest for a moment. @param {View} view */
  settle(view) {
    const idle = this.handlers.idle;
    if (!idle) {
      return;
    }
    clearTimeout(this.idleTimer);
    this.idleTimer = window.setTimeout(async () => {
      if (this.busy || this.pending || this.latest?.key !== view.key) {
        return;
      }
      this.busy = true;
      try {
        await idle(view);
      } catch (e) {
        this.handlers.failed(e, view);
      } finally {
        this.busy = false;
      }
      void this.pump();
    }, SETTLE_MS);
  }

  /**
   * Frames and latency percentiles over the kept latencies (or the last `n`).
   * @param {number} [n]
   * @returns {{frames: number, failures: number, p50: number, p95: number, count: number}}
   */
  stats(n) {
    const kept = n ? this.latencies.slice(-n) : this.latencies;
    const sorted = [...kept].sort((a, b) => a - b);
    const at = (q) => (sorted.length ? sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))] : NaN);
    return { frames: this.frames, failures: this.failures, p50: at(0.5), p95: at(0.95), count: sorted.length };
  }
}
