#!/usr/bin/env python3
# Checks that every relative markdown link of the given files resolves: the file exists and, for
# a .md target with #anchor, a heading gives that anchor under GitHub's rules (lowercase, spaces
# to "-", punctuation but "-" and "_" dropped, "-1", "-2" for repeats).
# Usage: scripts/check-doc-links.py README.md docs/*.md docs/history/*.md
import re,os,sys,glob
def anchors(path):
    a=set(); seen={}
    incode=False
    for l in open(path,encoding='utf-8'):
        if l.startswith('```'): incode=not incode; continue
        if incode: continue
        m=re.match(r'^(#{1,6})\s+(.*?)\s*#*\s*$',l)
        if not m: continue
        t=m.group(2).strip().lower()
        t=re.sub(r'[^\w\- ]','',t)   # drop punctuation except - and _
        t=t.replace(' ','-')
        if t in seen:
            seen[t]+=1; a.add(f"{t}-{seen[t]}")
        else:
            seen[t]=0; a.add(t)
    return a
files=sys.argv[1:]
bad=0; n=0
for f in files:
    txt=open(f,encoding='utf-8').read()
    txt=re.sub(r'```.*?```','',txt,flags=re.S)
    txt=re.sub(r'`[^`\n]*`',lambda m:'x'*len(m.group(0)) if '](' not in m.group(0) else m.group(0),txt)
    for m in re.finditer(r'\]\(\s*([^)\s]+)\s*\)',txt):
        tgt=m.group(1)
        if re.match(r'^[a-z]+:',tgt): continue
        n+=1
        path,_,frag=tgt.partition('#')
        full=os.path.normpath(os.path.join(os.path.dirname(f),path)) if path else f
        if not os.path.exists(full):
            print(f"{f}: missing file {tgt}"); bad+=1; continue
        if frag and full.endswith('.md'):
            if frag not in anchors(full):
                print(f"{f}: missing anchor {tgt}"); bad+=1
print(f"{n} relative links checked, {bad} broken")
sys.exit(1 if bad else 0)
