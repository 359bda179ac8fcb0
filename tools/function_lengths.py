#!/usr/bin/env python3
"""Lists C++ functions longer than a limit (lines from signature to closing brace).

A brace-matching heuristic, not a parser: a '{' opens a function body when the text
before it (since the previous ';', '{' or '}') ends in ')' or a trailing qualifier and
is not a control statement, a lambda or an initializer. Good enough to enforce the
"no function over 80 lines" rule of docs/ARCHITECTURE.md.

  tools/function_lengths.py [--limit 80] FILE...
"""
import argparse
import re
import sys

CONTROL = re.compile(r'^\s*(if|for|while|switch|catch|do|else|try)\b')
QUALIFIERS = re.compile(r'\)\s*(const|override|final|noexcept|mutable|->\s*[\w:<>,\s\*&]+)*\s*$')


def strip_code(text):
    """Blanks comments, strings and char literals, keeping line breaks."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            out.append(' ' * (j - i)); i = j
        elif text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j])); i = j
        elif text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = ')' + m.group(1) + '"'
            j = text.find(end, i)
            j = n if j < 0 else j + len(end)
            out.append(re.sub(r'[^\n]', ' ', text[i:j])); i = j
        elif c in '"\'':
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == '\\' else 1
            out.append(' ' * (j + 1 - i)); i = j + 1
        else:
            out.append(c); i += 1
    return ''.join(out)


def functions(text):
    code = strip_code(text)
    stack = []  # (is_function, start_line, name)
    head_start = 0
    line = 1
    results = []
    for i, c in enumerate(code):
        if c == '\n':
            line += 1
        elif c == '{':
            head = code[head_start:i]
            inside_function = any(s[0] for s in stack)
            is_function = (not inside_function and QUALIFIERS.search(head) is not None
                           and not CONTROL.search(head.strip().split('\n')[-1] if head.strip() else '')
                           and not re.search(r'\]\s*\(', head) and '=' not in head.split('(')[0])
            name = ''
            if is_function:
                m = re.search(r'([~\w:]+)\s*\(', head)
                name = m.group(1) if m else '?'
                start = line - head.strip('\n').count('\n') if head.strip() else line
                start = line - head[len(head) - len(head.lstrip()):].count('\n')
                stripped = head.lstrip()
                start = line - stripped.count('\n')
            else:
                start = line
            stack.append((is_function, start, name))
            head_start = i + 1
        elif c == '}':
            if stack:
                is_function, start, name = stack.pop()
                if is_function:
                    results.append((name, start, line - start + 1))
            head_start = i + 1
        elif c == ';':
            head_start = i + 1
    return results


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--limit', type=int, default=80)
    parser.add_argument('files', nargs='+')
    args = parser.parse_args()
    long_ones = 0
    for path in args.files:
        with open(path, encoding='utf-8', errors='replace') as f:
            text = f.read()
        for name, start, length in functions(text):
            if length > args.limit:
                print(f'{path}:{start}: {name} {length} lines')
                long_ones += 1
    return 1 if long_ones else 0


if __name__ == '__main__':
    sys.exit(main())
