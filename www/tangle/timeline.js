// The step slider and Play: which step of the answer's history the canvas
// shows (`live.k`, state.js), and the growth played back in about three
// seconds.

/**
 * The slider `slider`, the Play button `playBtn` and the count `out` of a
 * mounted panel; `paint()` repaints the canvas (canvas.js).
 */
export function createTimeline({ slider, playBtn, out, live, paint }) {
  let playing = 0;

  function setStep(v, draw = true) {
    const { T } = live;
    const k = live.k = Math.max(0, Math.min(T ? T.steps : 0, Math.round(v)));
    slider.value = String(k);
    const n = T ? T.count(k) : 0;
    out.textContent = T ? `step ${k.toLocaleString('en')} / ${T.steps.toLocaleString('en')} · ${n.toLocaleString('en')} shapes` : '—';
    out.dataset.count = String(n);
    out.dataset.step = String(k);
    if (draw) paint();
  }
  slider.addEventListener('input', () => { stopPlay(); setStep(Number(slider.value)); });

  function stopPlay() {
    if (!playing) return;
    cancelAnimationFrame(playing);
    playing = 0;
    playBtn.textContent = '▶';
    playBtn.setAttribute('aria-label', 'Play the growth');
  }
  function play() {
    const { T } = live;
    if (!T || !T.steps) return;
    if (live.k >= T.steps) setStep(0, false);
    playBtn.textContent = '❚❚';
    playBtn.setAttribute('aria-label', 'Pause');
    const per = Math.max(1, Math.round(T.steps / 180)); // about three seconds at 60 frames a second
    const tick = () => {
      if (!live.T || live.k >= live.T.steps) { stopPlay(); return; }
      setStep(live.k + per);
      playing = requestAnimationFrame(tick);
    };
    playing = requestAnimationFrame(tick);
  }
  playBtn.onclick = () => (playing ? stopPlay() : play());

  return {
    setStep, stopPlay,
    /** The answer's last step is `steps`. */
    setSteps(steps) { slider.max = String(steps); },
  };
}
