"""Every citation of the design document names a section of doc/design.md that exists."""

import glob
import os
import re

from conftest import REPO_ROOT

CITATION = re.compile(r'design\.md,? section (\d+)')
OUTSIDE = 'shared' + '/'  # the folder of background notes, which is not in the repository


def sources():
    """Return the repository's Python and Markdown files (package, tests, bench, docs)."""
    patterns = ('punctured_planner/**/*.py', 'test/*.py', 'bench/*.py', 'msg_docs/*.md',
                '*.md', 'doc/*.md', 'config/*')
    return sorted({path for pattern in patterns
                   for path in glob.glob(os.path.join(REPO_ROOT, pattern), recursive=True)})


def test_citations_name_existing_sections_of_doc_design():
    with open(os.path.join(REPO_ROOT, 'doc', 'design.md'), encoding='utf-8') as stream:
        sections = set(re.findall(r'^## (\d+)\. ', stream.read(), flags=re.MULTILINE))
    cited = 0
    for path in sources():
        with open(path, encoding='utf-8') as stream:
            text = stream.read()
        for found in re.finditer(r'(\S*)design\.md', text):
            if os.path.basename(path) not in ('design.md', 'test_design_doc.py'):
                assert found.group(1).endswith('doc/'), '%s: %s' % (path, found.group(0))
        for number in CITATION.findall(text):
            cited += 1
            assert number in sections, '%s cites a missing section %s' % (path, number)
        assert OUTSIDE not in text, '%s points outside the repository' % path
    assert cited >= 5
