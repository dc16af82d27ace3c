// Small DOM helpers: el(tag, attrs, ...children) builds an element; on() wires an event.
export const $ = (selector, root = document) => root.querySelector(selector);
export const $$ = (selector, root = document) => [...root.querySelectorAll(selector)];

export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (v === undefined || v === null || v === false) continue;
    if (k === "class") node.className = v;
    else if (k === "text") node.textContent = v;
    else if (k.startsWith("on")) node.addEventListener(k.slice(2), v);
    else if (k === "hidden" || k === "disabled" || k === "checked" || k === "multiple" || k === "selected") node[k] = Boolean(v);
    else node.setAttribute(k, v === true ? "" : String(v));
  }
  for (const c of children.flat()) if (c !== null && c !== undefined && c !== false) node.append(c);
  return node;
}

let counter = 0;
export const uid = (prefix = "f") => `${prefix}-${++counter}`;

export function download(name, text, type) {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = el("a", { href: url, download: name });
  document.body.append(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

export function debounce(fn, ms) {
  let timer = null;
  return (...args) => { clearTimeout(timer); timer = setTimeout(() => fn(...args), ms); };
}

// A "the same as a command" box: the only place the page shows command-line options.
export function commandBox(argv) {
  const quoted = argv.map((a) => (/[\s"'*^]/.test(a) ? `"${a.replace(/"/g, '\\"')}"` : a)).join(" ");
  return el("details", { class: "command" }, el("summary", { text: "The same as a command" }),
    el("pre", {}, el("code", { text: `motorlab ${quoted}` })));
}
