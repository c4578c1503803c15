// Requests to the winged API from the viewer: the bearer token the user gave, JSON in
// and out, and every refusal (problem+json or otherwise) turned into an ApiError.

/** Where the token is kept for this browser tab only. */
const TOKEN_KEY = "winged.viewer.token";

/** A refused or failed request: the HTTP status (0 when no answer came) and the
 * problem's title, detail and type when the server sent problem+json. */
export class ApiError extends Error {
  /**
   * @param {number} status HTTP status, 0 for a network failure.
   * @param {string} title Short summary.
   * @param {string} detail What went wrong, in the server's words.
   * @param {string} [type] The problem type URI.
   * @param {string} [what] The request that failed, e.g. "POST /v1/appearance".
   */
  constructor(status, title, detail, type = "", what = "") {
    super(`${status || "network"} ${title}: ${detail}`);
    this.name = "ApiError";
    this.status = status;
    this.title = title;
    this.detail = detail;
    this.type = type;
    this.what = what;
  }

  /** A line for the status bar, with a hint for the token errors. */
  describe() {
    const where = this.what ? ` (${this.what})` : "";
    if (this.status === 401) {
      return `401 ${this.title}${where}: this server needs a token. Enter a read token above. ${this.detail}`;
    }
    if (this.status === 403) {
      return `403 ${this.title}${where}: the token does not allow this. ${this.detail}`;
    }
    if (this.status === 0) {
      return `Cannot reach the server${where}: ${this.detail}`;
    }
    return `${this.status} ${this.title}${where}: ${this.detail}`;
  }
}

/** The token for this tab ("" when none). */
export function getToken() {
  return sessionStorage.getItem(TOKEN_KEY) ?? "";
}

/** Keeps `token` for this tab; an empty one forgets it. @param {string} token */
export function setToken(token) {
  const t = token.trim();
  if (t) {
    sessionStorage.setItem(TOKEN_KEY, t);
  } else {
    sessionStorage.removeItem(TOKEN_KEY);
  }
}

/**
 * Request headers with the token's Authorization (if any) added to `extra`.
 * @param {Record<string, string>} [extra]
 * @returns {Record<string, string>}
 */
export function authHeaders(extra = {}) {
  const headers = { ...extra };
  const token = getToken();
  if (token) {
    headers.Authorization = `Bearer ${token}`;
  }
  return headers;
}

/**
 * The error an unsuccessful answer stands for, read from its problem+json body when it
 * has one.
 * @param {Response} res
 * @param {string} what
 * @returns {Promise<ApiError>}
 */
export async function errorOf(res, what) {
  const type = res.headers.get("Content-Type") ?? "";
  let text = "";
  try {
    text = await res.text();
  } catch (e) {
    text = String(e);
  }
  if (type.includes("json")) {
    try {
      const p = JSON.parse(text);
      return new ApiError(res.status, p.title ?? res.statusText, p.detail ?? text, p.type ?? "", what);
    } catch {
      // Not JSON after all: the text itself is the detail.
    }
  }
  return new ApiError(res.status, res.statusText || "Error", text.slice(0, 300) || "(no detail)", "", what);
}

/**
 * Sends a request to the API and answers the response when it succeeded.
 * @param {string} method
 * @param {string} path Path and query, e.g. "/v1/world".
 * @param {{json?: unknown, headers?: Record<string, string>, signal?: AbortSignal}} [options]
 * @returns {Promise<Response>}
 * @throws {ApiError} on a refusal or when the server cannot be reached.
 */
export async function request(method, path, options = {}) {
  const what = `${method} ${path.split("?")[0]}`;
  const headers = authHeaders(options.headers ?? {});
  /** @type {RequestInit} */
  const init = { method, headers, signal: options.signal, cache: "no-store" };
  if (options.json !== undefined) {
    headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(options.json);
  }
  let res;
  try {
    res = await fetch(path, init);
  } catch (e) {
    throw new ApiError(0, "Network error", e instanceof Error ? e.message : String(e), "", what);
  }
  if (!res.ok) {
    throw await errorOf(res, what);
  }
  return res;
}

/**
 * GETs JSON.
 * @param {string} path
 * @returns {Promise<any>}
 */
export async function getJson(path) {
  const res = await request("GET", path, { headers: { Accept: "application/json" } });
  return res.json();
}
