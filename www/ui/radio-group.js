// Keyboard behaviour of a radio group built from buttons (WAI-ARIA radio
// group pattern): the container has role="radiogroup" and an aria-label, each
// choice role="radio" and aria-checked. One Tab stop for the group (the checked
// choice); arrow keys, Home and End move to another choice and select it (by
// clicking it, so the panel's own click handler does the selecting). Choices
// may be replaced at any time (a MutationObserver keeps the Tab stop right).
// Returns a function that removes the behaviour.
export function radioGroup(group) {
  const items = () => [...group.querySelectorAll('[role=radio]')].filter((b) => !b.disabled);
  const sync = () => {
    const all = items();
    const checked = all.find((b) => b.getAttribute('aria-checked') === 'true') || all[0];
    for (const b of all) b.tabIndex = b === checked ? 0 : -1;
  };
  const onKey = (e) => {
    const all = items();
    const i = all.indexOf(e.target.closest?.('[role=radio]'));
    if (i < 0 || e.altKey || e.ctrlKey || e.metaKey) return;
    const next = { ArrowRight: i + 1, ArrowDown: i + 1, ArrowLeft: i - 1, ArrowUp: i - 1, Home: 0, End: all.length - 1 }[e.key];
    if (next === undefined) return;
    e.preventDefault();
    const b = all[(next + all.length) % all.length];
    b.focus();
    b.click();
  };
  group.addEventListener('keydown', onKey);
  const mo = new MutationObserver(sync);
  mo.observe(group, { childList: true, subtree: true, attributes: true, attributeFilter: ['aria-checked'] });
  sync();
  return () => { group.removeEventListener('keydown', onKey); mo.disconnect(); };
}
