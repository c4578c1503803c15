// The world's change stream, `GET /v1/world/events`, read with fetch() so that it can
// carry the token (EventSource cannot send an Authorization header). Server-sent events
// are parsed here; after a dropped connection the stream is resumed with
// `Last-Event-ID`, so no change is lost or seen twice.

import { authHeaders, errorOf, ApiError } from "./api.js";

/** First and longest wait before reconnecting, ms. */
const FIRST_RETRY = 500;
const LONGEST_RETRY = 10000;

/**
 * @typedef {object} EventHandlers
 * @property {(change: any) => void} change One applied write (a `Change`).
 * @property {(detail: string) => void} resync The history no longer reaches back: read
 *   the world again and follow it from its revision.
 * @property {(state: "connecting" | "open" | "closed" | "error", error?: unknown) => void} state
 */

/** One event as it is being read. */
class Pending {
  constructor() {
    this.event = "message";
    /** @type {string[]} */
    this.data = [];
    /** @type {string | null} */
    this.id = null;
  }
}

/** A subscription to the change stream that reconnects until stopped. */
export class WorldEvents {
  /** @param {EventHandlers} on */
  constructor(on) {
    this.on = on;
    /** @type {string | null} The id (revision) of the last event seen. */
    this.lastId = null;
    this.running = false;
    /** @type {AbortController | null} */
    this.controller = null;
  }

  /**
   * Follows the changes after revision `since`.
   * @param {number} since
   */
  start(since) {
    this.stop();
    this.lastId = null;
    this.since = since;
    this.running = true;
    const controller = new AbortController();
    this.controller = controller;
    void this.run(controller.signal);
  }

  /** Ends the subscription. */
  stop() {
    this.running = false;
    this.controller?.abort();
    this.controller = null;
  }

  /** Connects, reads and reconnects, until stopped or refused for good. @param {AbortSignal} signal */
  async run(signal) {
    let wait = FIRST_RETRY;
    while (this.running && !signal.aborted) {
      this.on.state("connecting");
      try {
        const headers = authHeaders({ Accept: "text/event-stream" });
        let url = "/v1/world/events";
        if (this.lastId !== null) {
          headers["Last-Event-ID"] = this.lastId;
        } else {
          url += `?since=${this.since}`;
        }
        let res;
        try {
          res = await fetch(url, { headers, signal, cache: "no-store" });
        } catch (e) {
          throw new ApiError(
            0,
            "Network error",
            e instanceof Error ? e.message : String(e),
            "",
            "GET /v1/world/events",
          );
        }
        if (!res.ok || !res.body) {
          const error = await errorOf(res, "GET /v1/world/events");
          if (res.status >= 400 && res.status < 500 && res.status !== 408 && res.status !== 429) {
            // Refused for a reason a retry cannot change (the token, say): stop here.
            this.running = false;
            this.on.state("error", error);
            return;
          }
          throw error;
        }
        this.on.state("open");
        wait = FIRST_RETRY;
        await this.read(res.body);
        if (signal.aborted) {
          return;
        }
        this.on.state("closed");
      } catch (e) {
        if (signal.aborted) {
          return;
        }
        this.on.state("error", e);
      }
      if (!this.running) {
        return;
      }
      await new Promise((resolve) => setTimeout(resolve, wait));
      wait = Math.min(wait * 2, LONGEST_RETRY);
    }
  }

  /**
   * Reads events until the stream ends.
   * @param {ReadableStream<Uint8Array>} body
   */
  async read(body) {
    const reader = body.pipeThrough(new TextDecoderStream()).getReader();
    let buffer = "";
    let event = new Pending();
    for (;;) {
      const { value, done } = await reader.read();
      if (done) {
        return;
      }
      buffer += value;
      let nl;
      while ((nl = buffer.indexOf("\n")) >= 0) {
        let line = buffer.slice(0, nl);
        buffer = buffer.slice(nl + 1);
        if (line.endsWith("\r")) {
          line = line.slice(0, -1);
        }
        if (line === "") {
          this.dispatch(event);
          event = new Pending();
        } else {
          this.field(event, line);
        }
      }
    }
  }

  /**
   * Takes one `field: value` line into the event being read (comments, lines starting
   * with a colon, are keep-alives).
   * @param {Pending} event
   * @param {string} line
   */
  field(event, line) {
    if (line.startsWith(":")) {
      return;
    }
    const colon = line.indexOf(":");
    const name = colon < 0 ? line : line.slice(0, colon);
    let value = colon < 0 ? "" : line.slice(colon + 1);
    if (value.startsWith(" ")) {
      value = value.slice(1);
    }
    if (name === "event") {
      event.event = value;
    } else if (name === "data") {
      event.data.push(value);
    } else if (name === "id" && !value.includes("\0")) {
      event.id = value;
    }
  }

  /** Hands a complete event to its handler. @param {Pending} event */
  dispatch(event) {
    if (event.id !== null) {
      this.lastId = event.id;
    }
    if (event.data.length === 0) {
      return;
    }
    const data = event.data.join("\n");
    if (event.event === "change") {
      let change;
      try {
        change = JSON.parse(data);
      } catch (e) {
        this.on.state("error", new Error(`a change event that is not JSON: ${data.slice(0, 200)}`));
        return;
      }
      this.on.change(change);
    } else if (event.event === "resync") {
      this.running = false;
      this.on.resync(data);
    }
  }
}
