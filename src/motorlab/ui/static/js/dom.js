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

// What a person would call a control: its tag, type, name in words (aria-label, its label, a button's text)
// and the fit card or field it sits in. The same control drawn again has the same description.
function describe(node) {
  const label = node.id ? document.querySelector(`label[for="${CSS.escape(node.id)}"]`) : null;
  const words = node.getAttribute("aria-label") || (label && label.textContent) || (node.closest("label") || {}).textContent
    || (node.tagName === "BUTTON" || node.tagName === "SUMMARY" || node.tagName === "A" ? node.textContent : "") || node.getAttribute("name") || "";
  const place = node.closest("[data-group], [data-file]");
  return [node.tagName, node.type || "", words.trim(), place ? place.getAttribute("data-group") || place.getAttribute("data-file") : ""].join("|");
}

const textual = (node) => node.tagName === "TEXTAREA" || (node.tagName === "INPUT" && /^(text|search|number|email|url|tel|password|)$/.test(node.type));

// Redraw `root` with draw() and give the person back what they were doing: the focused control (found again
// by its description), its caret and selection, what they had typed into it but not yet committed, the
// sections they had opened and where they had scrolled to.
export function keepFocus(root, draw) {
  const active = document.activeElement;
  let kept = null;
  if (active && active !== root && root.contains(active)) {
    const key = describe(active);
    const twins = [...root.querySelectorAll(active.tagName)].filter((n) => describe(n) === key);
    kept = { key, tag: active.tagName, index: twins.indexOf(active), textual: textual(active), value: active.value,
      start: textual(active) ? active.selectionStart : null, end: textual(active) ? active.selectionEnd : null };
  }
  // the sections the person opened ("More options for this fit") stay open
  const summaryOf = (d) => { const s = d.querySelector(":scope > summary"); const place = d.closest("[data-group], [data-file]");
    return `${s ? s.textContent.trim() : ""}|${place ? place.getAttribute("data-group") || place.getAttribute("data-file") : ""}`; };
  const opened = [...root.querySelectorAll("details[open]")].map(summaryOf);
  const scroll = [window.scrollX, window.scrollY];
  // Chromium fires blur and change at a focused field taken out of the page: they must not commit half a number
  const swallow = (e) => { if (kept && e.target === active) e.stopImmediatePropagation(); };
  const types = ["change", "blur", "focusout"];
  for (const type of types) window.addEventListener(type, swallow, true);
  try { draw(); } finally { setTimeout(() => { for (const type of types) window.removeEventListener(type, swallow, true); }, 0); }
  for (const d of root.querySelectorAll("details:not([open])")) if (opened.includes(summaryOf(d))) d.open = true;
  if (!kept) { window.scrollTo(...scroll); return; }
  const twins = [...root.querySelectorAll(kept.tag)].filter((n) => describe(n) === kept.key);
  const again = twins[kept.index] || (twins.length === 1 ? twins[0] : null);
  if (!again) return;
  if (kept.textual && again.value !== kept.value) {
    const drawn = again.value;
    again.value = kept.value;
    // the typed text was never committed (a field that saves on change): commit it when the person leaves
    let committed = false;
    again.addEventListener("change", () => { committed = true; }, { once: true });
    again.addEventListener("blur", () => { if (!committed && again.value !== drawn) again.dispatchEvent(new Event("change", { bubbles: true })); }, { once: true });
  }
  again.focus({ preventScroll: true });
  if (kept.textual && kept.start !== null) { try { again.setSelectionRange(kept.start, kept.end); } catch (e) { /* a field without a caret */ } }
  window.scrollTo(...scroll);
}
