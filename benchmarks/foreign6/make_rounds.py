"""How round1.json / round2.json were made (kept for audit). Refuses to overwrite them."""
import json, os
P1=dict(soil="A",loads=[300,600,900,1200],slips=[0.05,0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9],repeats=1,torque=True,sinkage=True,order="random")
P2=dict(soil="A",loads=[400,800],slips=[0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8],repeats=2,torque=True,sinkage=True,order="random")
P3=dict(soil="B",loads=[150,300,450],slips=[0.05,0.1,0.2,0.3,0.45,0.6,0.75,0.9],repeats=2,torque=False,sinkage=True,order="random")
P3T=dict(P3,torque=True)
P4=dict(soil="B",loads=[300],slips=[0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9],repeats=3,torque=False,sinkage=True,order="sweep")
P5=dict(soil="A",loads=[500,1000],slips=[0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9],repeats=1,torque=True,sinkage=False,order="sweep")
P6=dict(soil="B",loads=[150,300,450,600],slips=[0.05,0.15,0.3,0.45,0.6,0.75,0.9],repeats=1,torque=True,sinkage=True,order="random")
tiny_T="The friction torque is of the order of the torque noise: a diagnosis may rightly see nothing ('none' acceptable)."
tiny_X="kappa*W is below the per-point Dp noise: a diagnosis may rightly see nothing ('none' acceptable)."
tiny_Z="dz is of the order of the sinkage noise and the per-preparation scatter ('none' acceptable)."
r1=[("none",P1,{}),("vasilev",P2,dict(H=0.012)),("crosstalk",P1,dict(kappa=0.05)),("terrain_mismatch",P2,dict(change=dict(k_rel=-0.45))),
("shear_peak",P1,dict(Kr=0.5,Kw_rel=1.5)),("lyasko",P1,dict(m1=0.5,m2=0.1)),("stress_distribution",P1,dict(a1=0.25,a2=0.1)),
("bearing_torque",P2,dict(T0=5.0,Tv=1.5)),("none",P3,{}),("ding",P1,dict(n1=0.35)),("bulldozing",P2,dict(zeta=1.0)),
("terrain_mismatch",P5,dict(change=dict(dphi_deg=5.0))),("sinkage_datum",P1,dict(dz=0.008)),("vasilev",P4,dict(H=0.006)),
("flexible_tyre",P1,dict(pg_kpa=80.0)),("lyasko",P3,dict(m1=0.2,m2=0.05)),("multipass",P2,dict(s_prev=0.15,Au=5e8)),
("stress_distribution",P3,dict(a1=0.35,a2=0.2)),("load_transfer",P1,dict(lam=0.4)),("terrain_mismatch",P3,dict(change=dict(K_rel=0.8))),
("crosstalk",P3T,dict(kappa=-0.07)),("ding",P4,dict(n1=0.25)),("shear_peak",P3T,dict(Kr=0.55,Kw_rel=1.5)),("none",P5,{}),
("terrain_mismatch",P1,dict(change=dict(dc_kpa=2.0,dphi_deg=-4.0))),("bulldozing",P3T,dict(zeta=3.0)),("stress_distribution",P5,dict(a1=0.15,a2=0.05)),
("sinkage_datum",P3T,dict(dz=-0.006)),("bearing_torque",P3T,dict(T0=0.8,Tv=0.2,also_none=True,why_none=tiny_T)),("multipass",P3T,dict(s_prev=0.4,Au=3e8))]
r2=[("ding",P2,dict(n1=0.15)),("flexible_tyre",P2,dict(pg_kpa=65.0)),("none",P2,{}),("terrain_mismatch",P1,dict(change=dict(dn=-0.2))),
("crosstalk",P1,dict(kappa=0.008,also_none=True,why_none=tiny_X)),("vasilev",P5,dict(H=0.025)),("shear_peak",P2,dict(Kr=0.45,Kw_rel=1.2)),
("stress_distribution",P2,dict(a1=0.4,a2=0.2)),("lyasko",P1,dict(m1=0.15,m2=0.03)),("multipass",P1,dict(s_prev=0.1,Au=8e8)),("none",P4,{}),
("bulldozing",P1,dict(zeta=1.4)),("terrain_mismatch",P2,dict(change=dict(kc_rel=2.0))),("bearing_torque",P1,dict(T0=8.0,Tv=2.0)),
("vasilev",P3,dict(H=0.015)),("sinkage_datum",P2,dict(dz=-0.009)),("lyasko",P4,dict(m1=0.6,m2=0.15)),("flexible_tyre",P6,dict(pg_kpa=40.0)),
("terrain_mismatch",P3,dict(change=dict(dphi_deg=-3.5))),("crosstalk",P2,dict(kappa=-0.06)),("stress_distribution",P4,dict(a1=0.2,a2=0.1)),
("load_transfer",P3T,dict(lam=0.3)),("none",dict(P1,repeats=2),{}),("shear_peak",P3T,dict(Kr=0.65,Kw_rel=1.2)),("ding",P3,dict(n1=0.45)),
("sinkage_datum",P3T,dict(dz=0.0015,also_none=True,why_none=tiny_Z)),("terrain_mismatch",P1,dict(change=dict(k_rel=0.7,K_rel=-0.45))),
("bulldozing",P6,dict(zeta=2.2)),("stress_distribution",P5,dict(a1=0.3,a2=0.3)),("bearing_torque",P3T,dict(T0=3.5,Tv=1.0))]
for tag,rr,s0 in (("round1",r1,901),("round2",r2,931)):
    out=[dict(name=f"f6{tag[0]}{tag[-1]}_{i+1:02d}",case=k,seed=s0+i,params=dict(p,**e)) for i,(k,p,e) in enumerate(rr)]
    assert len(out)==30
    if os.path.exists(f"{tag}.json"):
        print(f"{tag}.json exists; not overwritten"); continue
    json.dump(out,open(f"{tag}.json","w"),indent=1)

