# Builds a tiny text model with OPENCV and PINHOLE cameras from the fountain
# model converted to text: keeps 12 points and their observations plus 3
# unobserved keypoints per image, and re-indexes the keypoints.
import sys
src, dst = sys.argv[1], sys.argv[2]
def data_lines(path):
    return [l.rstrip('\n') for l in open(path) if not l.startswith('#')]
pts = [l.split() for l in data_lines(src + '/points3D.txt')]
keep = {int(p[0]) for p in sorted(pts, key=lambda p: int(p[0]))[:12]}
img_lines = data_lines(src + '/images.txt')
images = []
remap = {}
for i in range(0, len(img_lines), 2):
    head = img_lines[i].split()
    v = img_lines[i + 1].split()
    obs = [(v[j], v[j + 1], int(v[j + 2])) for j in range(0, len(v), 3)]
    new = []
    unobserved = 0
    for idx, (x, y, pid) in enumerate(obs):
        if pid in keep or (pid == -1 and unobserved < 3):
            if pid == -1: unobserved += 1
            remap[(int(head[0]), idx)] = len(new)
            new.append((x, y, pid))
    if int(head[0]) == 2: head[8] = '2'
    images.append((head, new))
with open(dst + '/cameras.txt', 'w') as f:
    f.write('1 OPENCV 3072 2048 2750.5 2752.25 1535.5 1023.5 -0.0107 0.0021 0.0001 -0.0002\n')
    f.write('2 PINHOLE 3072 2048 2760 2761.5 1536 1024\n')
with open(dst + '/images.txt', 'w') as f:
    for head, new in images:
        f.write(' '.join(head) + '\n')
        f.write(' '.join('%s %s %d' % o for o in new) + '\n')
with open(dst + '/points3D.txt', 'w') as f:
    for p in pts:
        if int(p[0]) not in keep: continue
        track = p[8:]
        t = []
        for j in range(0, len(track), 2):
            t += [track[j], str(remap[(int(track[j]), int(track[j + 1]))])]
        f.write(' '.join(p[:8] + t) + '\n')
