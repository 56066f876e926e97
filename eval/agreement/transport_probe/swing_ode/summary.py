import json,numpy as np,sys
rows=json.load(open('eval/agreement/transport_probe/swing_ode/ode_0.json'))+json.load(open('eval/agreement/transport_probe/swing_ode/ode_1.json'))
rows=[r for r in rows if r['seal_ok']] if 'seal_ok' in rows[0] else rows
ok=np.array([r['success'] for r in rows])
ode_t=np.array([r['ode']['held_transport'] and r['ode']['held_hold'] for r in rows])
ode_all=np.array([r['ode']['held_transport'] and r['ode']['held_hold'] and r['ode']['held_lift'] for r in rows])
cl_t=np.array([all(r['closed_ok'][1:]) for r in rows]); cl_all=np.array([all(r['closed_ok']) for r in rows])
for name,v in [('ode transport',ode_t),('ode all',ode_all),('closed transport',cl_t),('closed all',cl_all)]:
  print(f"{name:18s} carried&held {int((ok&v).sum())} carried&rejected {int((ok&~v).sum())} lost&held {int((~ok&v).sum())} lost&rejected {int((~ok&~v).sum())}")
for r in rows:
  o=r['ode']; 
  if r['success'] != (o['held_transport'] and o['held_hold']): print(r['object'],r['seed'],r['success'],r['rwr'],'ode',o['held_lift'],o['held_transport'],o['held_hold'],'closed',r['closed_ok'])
