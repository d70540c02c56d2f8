#!/usr/bin/env python3
"""Check every internal link of a built mdBook (default docs/book).

    python3 scripts/check_links.py [BOOK_DIR]

For each HTML page: every relative `href`/`src` must name a file of the book
(or of the repository, for links that leave it, e.g. ../../scenarios/x.toml),
and every `#fragment` must be an `id` of its target page. External links
(http:, https:, mailto:) are not fetched: CI has no network to spare.
Exit 1 with one line per broken link, 0 otherwise.
"""

import html.parser
import os
import sys
import urllib.parse


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.links = []
        self.ids = set()

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.add(a["id"])
        if "name" in a and tag == "a":
            self.ids.add(a["name"])
        for key in ("href", "src"):
            if a.get(key):
                self.links.append(a[key])


def parse(path, cache):
    if path not in cache:
        p = Page()
        with open(path, encoding="utf-8") as f:
            p.feed(f.read())
        cache[path] = p
    return cache[path]


def main():
    book = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "docs/book")
    if not os.path.isdir(book):
        print(f"error: {book}: no built book (run `mdbook build docs`)", file=sys.stderr)
        return 2
    cache = {}
    broken = []
    pages = 0
    for root, _, files in os.walk(book):
        for name in files:
            if not name.endswith(".html"):
                continue
            page = os.path.join(root, name)
            pages += 1
            for link in parse(page, cache).links:
                url = urllib.parse.urlsplit(link)
                if url.scheme or link.startswith("//"):
                    continue
                base = book if url.path.startswith("/") else os.path.dirname(page)
                target = page if not url.path else os.path.normpath(
                    os.path.join(base, urllib.parse.unquote(url.path).lstrip("/")))
                if os.path.isdir(target):
                    target = os.path.join(target, "index.html")
                rel = os.path.relpath(page, book)
                if not os.path.exists(target):
                    broken.append(f"{rel}: {link}: no such file")
                    continue
                if url.fragment and target.endswith(".html"):
                    if urllib.parse.unquote(url.fragment) not in parse(target, cache).ids:
                        broken.append(f"{rel}: {link}: no anchor #{url.fragment}")
    for b in sorted(set(broken)):
        print(b)
    print(f"{pages} pages, {len(set(broken))} broken links", file=sys.stderr)
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
