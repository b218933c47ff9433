// Micro's "Parameters": a number field for every number of every node of
// the scene; an edit rewrites the scene JSON (like typing) as one step.

const NODE_KEYS = new Set(['children', 'child', 'base', 'minus']);

/** Every node of a parsed scene: {path (JSON pointer), type, fields: [{pointer, label, value}]}. */
function nodesOf(root) {
  const out = [];
  const visit = (node, ptr) => {
    if (!node || typeof node !== 'object' || Array.isArray(node)) return;
    const fields = [];
    const leaves = (v, p, label) => {
      if (typeof v === 'number') fields.push({ pointer: p, label, value: v });
      else if (Array.isArray(v)) v.forEach((x, i) => leaves(x, `${p}/${i}`, `${label}[${i}]`));
      else if (v && typeof v === 'object') for (const [k, x] of Object.entries(v)) leaves(x, `${p}/${k}`, label ? `${label}.${k}` : k);
    };
    for (const [k, v] of Object.entries(node)) {
      if (NODE_KEYS.has(k)) continue;
      leaves(v, `${ptr}/${k}`, k);
    }
    out.push({ path: ptr || '/', type: String(node.type ?? '?'), fields });
    for (const k of NODE_KEYS) {
      const v = node[k];
      if (Array.isArray(v)) v.forEach((c, i) => visit(c, `${ptr}/${k}/${i}`));
      else if (v) visit(v, `${ptr}/${k}`);
    }
  };
  visit(root, '');
  return out;
}

function setPointer(root, pointer, value) {
  const keys = pointer.split('/').slice(1);
  let o = root;
  for (const k of keys.slice(0, -1)) o = o[k];
  o[keys[keys.length - 1]] = value;
}

/** The parameter fields of a mounted panel: {render(doc)}. */
export function createParams(ctx, { q }) {
  const state = () => ctx.state();
  const paramList = q('.micro-param-list');
  let paramScene = null; // the scene text the fields show

  function renderParams(doc) {
    if (doc.scene === paramScene) return;
    paramScene = doc.scene;
    let root;
    try { root = JSON.parse(doc.scene); } catch {
      paramList.replaceChildren(Object.assign(document.createElement('p'), { className: 'muted', textContent: 'The scene JSON does not parse; fix it in the editor.' }));
      return;
    }
    paramList.replaceChildren(...nodesOf(root).map((n) => {
      const fs = document.createElement('fieldset');
      fs.className = 'micro-node';
      fs.dataset.node = n.path;
      const legend = document.createElement('legend');
      legend.textContent = `${n.type}${n.path === '/' ? '' : ` (${n.path})`}`;
      fs.append(legend);
      for (const f of n.fields) {
        const label = document.createElement('label');
        label.className = 'inline';
        const input = document.createElement('input');
        input.type = 'number';
        input.step = 'any';
        input.value = String(f.value);
        input.dataset.pointer = f.pointer;
        input.onchange = () => {
          const v = Number(input.value);
          const cur = state();
          if (!cur || input.value.trim() === '' || !Number.isFinite(v)) { input.value = String(f.value); return; }
          let obj;
          try { obj = JSON.parse(cur.scene); } catch { return; }
          setPointer(obj, f.pointer, v);
          ctx.commit({ ...cur, scene: JSON.stringify(obj, null, 2), example: null });
        };
        label.append(`${f.label} `, input);
        fs.append(label);
      }
      return fs;
    }));
  }

  return { render: renderParams };
}
