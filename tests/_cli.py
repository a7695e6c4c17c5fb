"""What the tests check of every refused command: exit 2 and one line."""


def assert_refused(r, *fragments: str) -> str:
    """Exit 2 and one line on stderr (``error: ...``, no traceback) holding
    every fragment; the line.  ``r``: a typer CliRunner result or a
    subprocess.CompletedProcess."""
    code = r.returncode if hasattr(r, "returncode") else r.exit_code
    assert code == 2, (code, r.stdout, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert "Traceback" not in r.stderr and lines[0].startswith("error: ")
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]
