// Programs that nest as deeply as the pattern language allows, one family
// per kind of nesting; mirrors `deep_families` in src/pattern/record/tests.rs.
const C = 'circle(0.5, 0.5, 0.1);';
const rep = (s, k) => s.repeat(Math.max(0, k));
export const FAMILIES = {
  'parentheses': (k) => `let a = ${rep('(', k)}1${rep(')', k)};\n${C}`,
  'negations': (k) => `let a = ${rep('-', k)}1;\n${C}`,
  'operator chain': (k) => `let a = 1${rep(' + 1', k)};\n${C}`,
  'powers': (k) => `let a = 1${rep(' ^ 1', k)};\n${C}`,
  'calls': (k) => `let a = ${rep('abs(', k)}1${rep(')', k)};\n${C}`,
  'blocks': (k) => `${rep('{ ', k)}${C}${rep(' }', k)}`,
  'ifs': (k) => `${rep('if 1 { ', k)}${C}${rep(' }', k)}`,
  'fors': (k) => `${rep('for i in 0..1 { ', k)}${C}${rep(' }', k)}`,
  'translates': (k) => `${rep('translate(0, 0) { ', k)}${C}${rep(' }', k)}`,
  'rotates': (k) => `${rep('rotate(0.1) { ', k)}${C}${rep(' }', k)}`,
  'unions': (k) => `${rep('union(fill: "#000") { ', Math.min(k, 1))}${rep('union() { ', k - 1)}${C}${rep(' }', k)}`,
  'recursion': (k) => `fn f(n) { if n > 0 { f(n - 1); } ${C} }\nf(${k});`,
  'recursion through blocks': (k) => `fn f(n) { if n > 0 { { { { { { { { { f(n - 1); } } } } } } } } } }\nf(${k});\n${C}`,
  'recursion through transforms': (k) => `fn f(n) { if n > 0 { translate(0.001, 0) { rotate(0.01) { f(n - 1); } } } ${C} }\nf(${k});`,
  'recursion in arguments': (k) => `fn f(n) { if n > 0 { return f(n - 1) + 1; } return 0; }\nlet a = f(${k});\n${C}`,
};

/** In the page: run `render-pattern` (parse, record, compile, draw, SVG) on a program. */
export async function runIn(page, program) {
  return page.evaluate(async (program) => {
    try {
      await window.filigree.pool.run('render-pattern', { program, params: {}, size: 8 });
      return { ok: true };
    } catch (e) {
      return { ok: false, kind: e.kind, message: e.message, line: e.line, column: e.column };
    }
  }, program);
}
