// The status line: the latest message or error (every refusal from the server is shown
// here, with its status, title and detail), the change stream's state, and the picture
// statistics.

import { ApiError } from "./api.js";

/** Errors kept in the list under the status line. */
const KEPT_ERRORS = 5;

/** The status line's parts. */
export class Status {
  /**
   * @param {HTMLElement} message Where messages and errors go.
   * @param {HTMLElement} stream Where the change stream's state goes.
   * @param {HTMLElement} stats Where the picture statistics go.
   * @param {HTMLElement} log The list of recent errors.
   */
  constructor(message, stream, stats, log) {
    this.message = message;
    this.stream = stream;
    this.statsEl = stats;
    this.log = log;
    /** Errors shown so far. */
    this.errors = 0;
  }

  /** Shows an ordinary message. @param {string} text */
  info(text) {
    this.message.textContent = text;
    this.message.classList.remove("error");
  }

  /**
   * Shows an error: an ApiError with its status and the server's detail, anything else
   * as it describes itself. Also logged to the console.
   * @param {unknown} error
   * @param {string} [context] What the viewer was doing.
   */
  error(error, context = "") {
    const text = error instanceof ApiError ? error.describe() : error instanceof Error ? error.message : String(error);
    const line = context ? `${context}: ${text}` : text;
    this.message.textContent = line;
    this.message.classList.add("error");
    this.errors += 1;
    const item = document.createElement("li");
    item.textContent = `${new Date().toLocaleTimeString()} ${line}`;
    this.log.prepend(item);
    while (this.log.children.length > KEPT_ERRORS) {
      this.log.lastElementChild?.remove();
    }
    console.warn(`winged viewer: ${line}`);
  }

  /** Clears an error once things work again. */
  clearError() {
    if (this.message.classList.contains("error")) {
      this.info("");
    }
  }

  /** Shows the stream's state. @param {string} text @param {boolean} [bad] */
  streamState(text, bad = false) {
    this.stream.textContent = text;
    this.stream.classList.toggle("error", bad);
  }

  /** Shows the picture statistics. @param {string} text */
  stats(text) {
    this.statsEl.textContent = text;
  }
}
