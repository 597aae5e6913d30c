// The script editor: a textarea with a line-number gutter that scrolls with it, and a
// marked line and caret for the script's error.

export class Editor {
  constructor(textarea, gutter, problemBox, onChange) {
    this.area = textarea;
    this.gutter = gutter;
    this.problemBox = problemBox;
    this.errorLine = null;
    this.lines = 0;
    textarea.addEventListener('input', () => { this.renumber(); onChange(); });
    textarea.addEventListener('scroll', () => { gutter.scrollTop = textarea.scrollTop; });
    textarea.addEventListener('keydown', (e) => {
      // Tab indents instead of leaving the editor.
      if (e.key === 'Tab' && !e.ctrlKey && !e.altKey && !e.metaKey) {
        e.preventDefault();
        const { selectionStart: s, selectionEnd: t, value } = textarea;
        textarea.value = value.slice(0, s) + '  ' + value.slice(t);
        textarea.selectionStart = textarea.selectionEnd = s + 2;
        this.renumber();
        onChange();
      }
    });
    problemBox.addEventListener('click', () => {
      if (this.errorLine) this.goto(this.errorLine, this.errorColumn || 1);
    });
    this.renumber();
  }

  get text() { return this.area.value; }

  set text(value) {
    this.area.value = value;
    this.renumber();
  }

  renumber() {
    const count = this.area.value.split('\n').length;
    if (count === this.lines && !this.dirtyMarks) return;
    this.lines = count;
    this.dirtyMarks = false;
    const parts = [];
    for (let i = 1; i <= count; i++) {
      parts.push(i === this.errorLine ? `<span class="err" data-line="${i}">${i}</span>` : String(i));
    }
    // A spare line so the gutter can scroll as far as the textarea.
    this.gutter.innerHTML = parts.join('\n') + '\n ';
    this.gutter.scrollTop = this.area.scrollTop;
  }

  // Shows a problem from the server: {message, line, column}.
  showProblem(problem) {
    this.errorLine = problem.line || null;
    this.errorColumn = problem.column || null;
    const where = problem.line
      ? `line ${problem.line}${problem.column ? `, column ${problem.column}` : ''}: `
      : '';
    this.problemBox.textContent = where + problem.message;
    this.problemBox.dataset.line = problem.line || '';
    this.problemBox.dataset.column = problem.column || '';
    this.problemBox.hidden = false;
    this.dirtyMarks = true;
    this.renumber();
  }

  clearProblem() {
    if (this.problemBox.hidden && this.errorLine === null) return;
    this.errorLine = null;
    this.errorColumn = null;
    this.problemBox.hidden = true;
    this.problemBox.dataset.line = '';
    this.dirtyMarks = true;
    this.renumber();
  }

  // Puts the caret at a 1-based line and column and scrolls there.
  goto(line, column) {
    const lines = this.area.value.split('\n');
    let offset = 0;
    for (let i = 0; i < line - 1 && i < lines.length; i++) offset += lines[i].length + 1;
    offset += Math.max(0, Math.min((column || 1) - 1, (lines[line - 1] || '').length));
    this.area.focus();
    this.area.setSelectionRange(offset, offset);
    const lineHeight = 18;
    this.area.scrollTop = Math.max(0, (line - 3) * lineHeight);
  }
}
