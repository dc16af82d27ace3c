// Requests to the app. run() asks for NDJSON progress lines (when the server streams them) and can be aborted.
import { plain } from "./words.js";

export class ApiError extends Error {}

async function parse(response) {
  const text = await response.text();
  let body;
  try { body = JSON.parse(text); } catch (e) { body = { error: text.slice(0, 300) || response.statusText }; }
  if (!response.ok) throw new ApiError(plain(body.error || response.statusText));
  return body;
}

// This launch's robot token, held by the served page only (docs/ui.md, "Security"); the robot routes need it.
const token = (document.querySelector('meta[name="motorlab-token"]') || {}).content || "";
export const send = (url, init = {}) => fetch(url, { ...init, headers: { ...init.headers, "X-Motorlab-Token": token } });

export async function getJson(url) { return parse(await send(url)); }

export async function post(url, form, { signal } = {}) {
  return parse(await send(url, { method: "POST", body: form, signal }));
}

// POST with `Accept: application/x-ndjson`: progress lines go to onProgress, an early part of the answer
// (a session's table before its report) to onPartial, the last line is the answer.
// A server that does not stream answers with plain JSON, which is read as before.
export async function run(url, form, { signal, onProgress, onPartial } = {}) {
  const response = await send(url, { method: "POST", body: form, signal, headers: { Accept: "application/x-ndjson" } });
  const type = response.headers.get("content-type") || "";
  if (!type.includes("ndjson") || !response.body) return parse(response);
  const reader = response.body.getReader();
  const decoder = new TextDecoder();
  let buffer = "";
  let answer = null;
  const handle = (line) => {
    if (!line.trim()) return;
    const msg = JSON.parse(line);
    if (msg.progress && onProgress) onProgress(msg.progress);
    else if (msg.partial && onPartial) onPartial(msg.partial);
    else if ("result" in msg) answer = msg;
    else if ("error" in msg) answer = msg;
  };
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    buffer += decoder.decode(value, { stream: true });
    let cut;
    while ((cut = buffer.indexOf("\n")) >= 0) { handle(buffer.slice(0, cut)); buffer = buffer.slice(cut + 1); }
  }
  handle(buffer);
  if (!answer) throw new ApiError(response.ok ? "the answer ended before its result" : response.statusText);
  if ("error" in answer) throw new ApiError(plain(answer.error));
  return answer.result;
}

export const isAbort = (e) => e && (e.name === "AbortError" || e instanceof DOMException);
