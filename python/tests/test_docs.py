"""docs/python.md's examples print what the page shows: every ```pycon block runs as a doctest
(one namespace for the page, in order), in a scratch directory that links the repository's
folders, so the figures they write land there."""

import doctest
import re


def test_the_python_docs_examples_print_what_they_show(root, tmp_path, monkeypatch):
    for name in ("data", "tests", "configs", "docs"):
        (tmp_path / name).symlink_to(root / name)
    monkeypatch.chdir(tmp_path)
    page = (root / "docs" / "python.md").read_text()
    blocks = re.findall(r"^```pycon\n(.*?)^```$", page, flags=re.S | re.M)
    assert len(blocks) >= 5
    text = "\n".join(blocks)
    test = doctest.DocTestParser().get_doctest(text, {}, "docs/python.md", "docs/python.md", 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0
    assert result.attempted > 30  # the page's examples were found and run
    assert (tmp_path / "fit.svg").exists()
