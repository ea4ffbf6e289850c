#!/usr/bin/env python3
"""Compiles every ```cpp snippet of a Markdown page against an installed taxopt.

    python3 scripts/check_doc_snippets.py docs/library.md PREFIX

Each snippet's #include lines go first; the rest becomes the body of a function whose
parameters are the names a snippet may use undeclared: a job's inputs `toolpath`, `machine`
and `part`. A snippet that does not compile (a renamed field, a wrong signature) fails.
"""
import os
import re
import subprocess
import sys
import tempfile


def snippets(text):
    return re.findall(r"```cpp\n(.*?)```", text, flags=re.S)


def program(snippet):
    includes = [l for l in snippet.splitlines() if l.startswith("#include")]
    body = [l for l in snippet.splitlines() if not l.startswith("#include")]
    return "\n".join(
        includes
        + [
            "void snippet(const taxopt::Toolpath& toolpath, const taxopt::Machine& machine,",
            "             const taxopt::Part& part) {",
            "  (void)toolpath, (void)machine, (void)part;",
        ]
        + ["  " + l for l in body]
        + ["}", ""]
    )


def main():
    page, prefix = sys.argv[1], sys.argv[2]
    found = snippets(open(page, encoding="utf-8").read())
    if not found:
        sys.exit(f"{page}: no cpp snippet")
    failed = 0
    for k, s in enumerate(found, 1):
        with tempfile.NamedTemporaryFile("w", suffix=".cpp", delete=False) as f:
            f.write(program(s))
        r = subprocess.run(
            ["g++", "-std=c++17", "-fsyntax-only", "-Wall", "-Wextra", "-Werror",
             "-I", os.path.join(prefix, "include"), "-I", "/usr/include/eigen3", f.name],
            capture_output=True, text=True)
        os.unlink(f.name)
        if r.returncode != 0:
            failed += 1
            print(f"{page}: snippet {k} does not compile:\n{s}\n{r.stderr}", file=sys.stderr)
    print(f"{page}: {len(found) - failed} of {len(found)} cpp snippets compile")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
