#!/usr/bin/env python3
# Usage: python benches/repeat_footscan.py TRIAL.txt K OUT.txt
# A footscan export whose frames (its [DataN] sections; [Data] is kept once) are repeated K times.
import re, sys
src, k, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
text = open(src).read()
head, first, body = re.split(r'(\[Data\]\n.*?)(?=\n\s*\[Data\d+\]\n)', text, maxsplit=1, flags=re.S)
frames = re.split(r'\n\s*\[Data\d+\]\n', body)[1:]
frames = [f.strip('\n') for f in frames] * k
head = re.sub(r'MaxIdx=\d+', 'MaxIdx=%d' % len(frames), head)
with open(out, 'w') as f:
    f.write(head + first.rstrip('\n') + '\n')
    for i, fr in enumerate(frames, 1):
        f.write('\n[Data%d]\n%s\n' % (i, fr))
