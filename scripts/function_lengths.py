#!/usr/bin/python3
"""Function bodies longer than a bound in C++ sources, for scripts/lint.sh.

Usage: function_lengths.py <max lines> <allowed file> <dir>...
A body is counted from the line of its opening brace to the line of its closing one. A definition is an
outermost brace pair that is not a namespace, class, struct, enum or initializer (`= {`); comments and string
literals are ignored. Bodies over the bound fail unless the allowed file names them (path:function prefix per
line, '#' comments): a ratchet for the ones not yet split, which fails too when a named one is gone or short.
"""
import os
import re
import sys


def strip(line, in_comment):
    out, i = [], 0
    while i < len(line):
        if in_comment:
            end = line.find('*/', i)
            if end < 0:
                return ''.join(out), True
            i, in_comment = end + 2, False
        elif line.startswith('/*', i):
            in_comment = True
            i += 2
        elif line.startswith('//', i):
            break
        elif line[i] in '"\'':
            q, j = line[i], i + 1
            while j < len(line) and line[j] != q:
                j += 2 if line[j] == '\\' else 1
            out.append('""')
            i = j + 1
        else:
            out.append(line[i])
            i += 1
    return ''.join(out), in_comment


SCOPE = re.compile(r'^\s*((inline\s+)?namespace\b|extern\s+"|(template\s*<.*>\s*)?(class|struct|union|enum)\b[^;()]*$)')


def bodies(path):
    lines = open(path, encoding='utf-8').read().split('\n')
    stack, in_comment, header = [], False, ''
    for n, raw in enumerate(lines, 1):
        code, in_comment = strip(raw, in_comment)
        if code.lstrip().startswith('#'):  # preprocessor: not part of any declaration
            header = ''
            continue
        header = (header + ' ' + code).strip()[-300:]
        for ch in code:
            if ch == '{':
                before = header[:header.rfind('{')] if '{' in header else header
                last = re.split(r'[;}]', before)[-1]
                scope = bool(SCOPE.match(last)) or last.rstrip().endswith('=')
                outermost = all(s[1] for s in stack)
                stack.append((n, scope, outermost and not scope, last.strip()))
                header = ''
            elif ch == '}' and stack:
                start, _, is_function, name = stack.pop()
                if is_function:
                    yield start, n - start + 1, name
                header = ''


def main():
    bound, allowed_file, roots = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
    allowed = [l.split('#')[0].strip() for l in open(allowed_file, encoding='utf-8')]
    allowed = [a for a in allowed if a]
    used, failures = set(), []
    for root in roots:
        for d, _, files in os.walk(root):
            for f in sorted(files):
                if not f.endswith(('.cpp', '.h')):
                    continue
                path = os.path.join(d, f)
                for start, length, name in bodies(path):
                    if length <= bound:
                        continue
                    where = f'{path}:{start}'
                    key = next((a for a in allowed if a.startswith(path + ':') and
                                a.split(':', 1)[1] in name), None)
                    if key:
                        used.add(key)
                    else:
                        failures.append(f'{where}: {length} lines (bound {bound}): {name[:80]}')
    for a in allowed:
        if a not in used:
            failures.append(f'{allowed_file}: {a} is within the bound now (or gone): take it off the list')
    for f in failures:
        print(f)
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
