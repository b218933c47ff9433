// A tool's heading and its Help. Every tool view has one h1 (its title) and
// a Help button beside it that opens a dialog: what the tool does, in a
// few lines, and what each of its controls is for. Keyboard: Tab reaches
// the button, Enter or Space opens the dialog, Escape or Close closes it and
// focus goes back to the button. The texts live here, one entry per tool id.
//
//   addToolHead(section, tool)   put the h1 and the Help button first in the
//                                tool's section (www/app/main.js, at each mount)

const HELP = {
  pixel: {
    about: 'Pixel adds texture to pixel art: it places small oriented elements (a 3×3 sheet, or one sprite turned eight ways) over the masked part of the picture, in the picture’s own colours, following the directions of your strokes.',
    controls: [
      ['Fish example, Trunk example', 'load a whole example: picture, mask, element sheet, strokes and settings.'],
      ['Strokes (S), Paint mask (M), Erase mask (E), size', 'what a drag on the picture does, and the brush size in pixels.'],
      ['− / +', 'zoom the pixel grid.'],
      ['result, mask, strokes, vector field', 'what the picture shows.'],
      ['Source, Mask, Element sheet, one sprite', 'your own images. Drop or paste an image anywhere in the window to use it as the source.'],
      ['Parameters', 'placement (random or packed, density, margins), the colour map and the seed; the result follows at once.'],
      ['Export PNG', 'the result, scaled up by whole pixels.'],
    ],
  },
  fit: {
    about: 'Fit finds the parameters of a pattern program that best match a target picture: a global search first (candidates compared by their spectra, which find a repeating design’s period and angle wherever it sits, then its phase swept), then gradient descent on the distance fields of the pattern’s colours.',
    controls: [
      ['Generator, Edit the program', 'pick a shipped pattern program or write your own (Apply program); its parameters become the sliders.'],
      ['Sliders', 'the pattern’s parameters; the pattern is drawn over the target with pink outlines.'],
      ['Brush colours, size, Clear', 'draw the target by hand in the program’s colours (the last colour erases).'],
      ['Upload target…', 'use an image as the target (or drop or paste one anywhere in the window); it is snapped to the program’s colours.'],
      ['Make target from these values', 'draw the sliders’ pattern as the target, to see whether the fit finds the values again.'],
      ['Budget, Loss, Seed, Run fit, Stop, Apply fitted values', 'run the fit (only once there is a target); it goes on while you use another tool, its progress on the Fit button. Stop keeps the values from before, and Apply fitted values puts in the best found so far.'],
      ['Export SVG, Export JSON', 'the fitted pattern as vectors, or the program with its values.'],
    ],
  },
  inspect: {
    about: 'Inspect image reads an image’s size and palette: the colours Fit and Pixel work with.',
    controls: [
      ['Choose a file…', 'pick an image; or drop one anywhere in the window, or paste one (Ctrl+V).'],
    ],
  },
  tangle: {
    about: 'Tangle grows pen-and-ink tangle drawings from a group grammar: shapes are split, outlined, filled and decorated step by step until only final shapes remain.',
    controls: [
      ['Grammar, Grammar text', 'pick a shipped grammar or edit one; Generate (Ctrl+Enter in the editor) grows it again.'],
      ['Seed, ⟳', 'the random draw; ⟳ picks a new one.'],
      ['Step slider, ▶, Steps list', 'walk the growth step by step; choose a step in the list (arrow keys) to select it on the drawing.'],
      ['Click a shape', 'select the step that made it; click again to go further back.'],
      ['Re-expand, Earlier step, Deselect', 'grow the selected step again with a new draw, select the step before it, or none.'],
      ['Start from', 'the grammar’s start, a rectangle, a typed word (applied as you type), an SVG file or a polygon drawn on the canvas.'],
      ['Wobble, Pen width, Export SVG / PNG', 'the hand-drawn look, and the drawing as a file.'],
    ],
  },
  micro: {
    about: 'Micro models particulate, fibrous, porous and laminar materials as implicit functions and renders them by sphere tracing, from the whole sample down to its smallest scale.',
    controls: [
      ['Scene buttons, Scene JSON', 'pick a shipped scene or edit its JSON; an error is shown under its line.'],
      ['The picture', 'drag or arrow keys to orbit, shift-drag or shift+arrows to pan, the wheel or − / + to zoom; Reset view.'],
      ['Steps, Slice view, z', 'the sphere-tracing step rule, or a cut through the field at height z.'],
      ['Surface, Roughness, Specular, Absorption, Path tracing', 'the shading (Roughness and Specular belong to GGX).'],
      ['Parameters', 'a number field for every number of the scene.'],
      ['Reconstruct', 'fit numbers of the scene to a target with the Fourier loss, then Apply fitted values (after Stop, the best so far); it goes on while you use another tool.'],
      ['Export PNG, Export scene JSON', 'the picture, or the scene as a file.'],
    ],
  },
  texture: {
    about: 'Texture finds a procedural texture model and its parameters from an example image, and lets you change its look with twelve perceptual sliders.',
    controls: [
      ['Example', 'drop an image anywhere in the window, paste one, choose a file, or render one of the models as the example.'],
      ['Perceptual scales', 'twelve sliders from 1 to 9; the nearest texture is retrieved and rendered live, with a chart of requested and retrieved scales.'],
      ['Stay within the predicted model', 'retrieve only textures of the model the example was read as.'],
      ['Parameters, Tile 2×2', 'the retrieved model’s parameters, and a tiled view.'],
      ['Export PNG, Export JSON', 'the texture, or its model and parameters.'],
    ],
  },
};

const esc = (s) => s.replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));

/** The tool's h1 and Help button (with its dialog), first in `section`. */
export function addToolHead(section, tool) {
  section.querySelector(':scope > .tool-head')?.remove();
  const head = document.createElement('div');
  head.className = 'tool-head';
  const h1 = document.createElement('h1');
  h1.className = 'tool-title';
  h1.textContent = tool.title;
  head.append(h1);
  const help = HELP[tool.id];
  if (help) {
    const button = document.createElement('button');
    button.type = 'button';
    button.dataset.act = 'help';
    button.setAttribute('aria-haspopup', 'dialog');
    button.setAttribute('aria-label', `Help: what ${tool.title} does and its controls`);
    button.textContent = 'Help';
    const dialog = document.createElement('dialog');
    dialog.className = 'help-dialog';
    dialog.dataset.testid = 'help';
    const titleId = `help-title-${tool.id}`;
    dialog.setAttribute('aria-labelledby', titleId);
    dialog.innerHTML = `
      <h2 id="${titleId}">${esc(tool.title)}: help</h2>
      <p>${esc(help.about)}</p>
      <h3>Controls</h3>
      <dl>${help.controls.map(([k, v]) => `<dt>${esc(k)}</dt><dd>${esc(v)}</dd>`).join('')}</dl>
      <p class="muted">Every tool: Undo / Redo (Ctrl+Z, Ctrl+Shift+Z), Save project (Ctrl+S), Open project… (Ctrl+O), Copy link. Your work is saved in this browser as you go.</p>
      <form method="dialog"><button type="submit" class="primary">Close</button></form>`;
    button.onclick = () => dialog.showModal();
    // The panel's single-key shortcuts stay behind the dialog (Escape still closes it).
    dialog.addEventListener('keydown', (e) => e.stopPropagation());
    dialog.addEventListener('close', () => button.focus());
    // A click on the backdrop (outside the dialog's box) closes it too.
    dialog.addEventListener('click', (e) => {
      const r = dialog.getBoundingClientRect();
      if (e.target === dialog && (e.clientX < r.left || e.clientX > r.right || e.clientY < r.top || e.clientY > r.bottom)) dialog.close();
    });
    head.append(button, dialog);
  }
  section.prepend(head);
  return head;
}
