// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.revrobotics.spark.config;
public abstract class SparkBaseConfig { public final ClosedLoopConfig closedLoop = new ClosedLoopConfig(); }
